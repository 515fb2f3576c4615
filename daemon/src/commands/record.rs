//! `emoshift record`: a live source (an OSC frame socket, a NatNet server or QTM) captured to one
//! file for training; Ctrl-C leaves the file complete. The capture is [`crate::serve::capture`].

use anyhow::{Context, Result};
use tokio_util::sync::CancellationToken;

use crate::cli::RecordArgs;
use crate::exit::UsageError;
use crate::offline::progress::Progress;
use crate::serve::capture::{self, CaptureConfig, Notice, Source};

/// The live source of `--listen`, `--natnet` (with its options) or `--qtm`, checked.
pub(crate) fn source(
    listen: Option<&String>,
    natnet: Option<&String>,
    qtm: Option<&String>,
    natnet_options: &crate::cli::NatNetArgs,
) -> Result<Source> {
    Ok(match (listen, natnet, qtm) {
        (Some(l), None, None) => Source::Osc(
            l.parse()
                .map_err(|_| UsageError(format!("--listen: {l:?} is not an IP:PORT address")))?,
        ),
        (None, Some(server), None) => {
            let raw = natnet_options.raw(Some(server.clone()));
            let n = raw.validate().map_err(|e| UsageError(e.to_string()))?;
            Source::NatNet(n.expect("a server was given"))
        }
        (None, None, Some(server)) => {
            let raw = crate::serve::sources::qtm::RawQtm {
                server: Some(server.clone()),
                performers: Default::default(),
            };
            let q = raw.validate().map_err(|e| UsageError(e.to_string()))?;
            Source::Qtm(q.expect("a server was given"))
        }
        _ => return Err(UsageError("give one source: --listen, --natnet or --qtm".into()).into()),
    })
}

/// The arguments, checked.
fn config(args: &RecordArgs) -> Result<CaptureConfig> {
    let source = source(
        args.listen.as_ref(),
        args.natnet.as_ref(),
        args.qtm.as_ref(),
        &args.natnet_options,
    )?;
    if replay::Format::from_path(&args.out).is_none() {
        return Err(UsageError(format!(
            "--out {}: record to a .c3d, .trc or .csv file",
            args.out.display()
        ))
        .into());
    }
    if args.frames == Some(0) || args.seconds.is_some_and(|s| !(s.is_finite() && s > 0.0)) {
        return Err(UsageError("--frames and --seconds must be positive".into()).into());
    }
    crate::offline::output::check_out(&args.out, &[], args.force)?;
    Ok(CaptureConfig {
        source,
        out: args.out.clone(),
        frames: args.frames,
        seconds: args.seconds,
        performer: args.performer.clone(),
    })
}

/// The capture's progress as `train` shows its own: a bar on a terminal (frames, rate, gaps,
/// time), a line every few seconds in a pipe; notices as lines.
struct Shown {
    progress: Box<dyn Progress + Send>,
    /// Stop after this many frames (the bar's total).
    total: Option<u64>,
    /// Frames shown so far (`None` before the first).
    frames: Option<u64>,
}

impl Shown {
    fn new(total: Option<u64>) -> Shown {
        Shown {
            progress: super::progress::for_stderr("record"),
            total,
            frames: None,
        }
    }

    fn notice(&mut self, notice: Notice<'_>) {
        let p = match notice {
            Notice::Line(line) => return eprintln!("emoshift record: {line}"),
            Notice::Progress(p) => p,
        };
        let before = *self.frames.get_or_insert_with(|| {
            let name = format!("recording {}", p.stream);
            self.progress.step(&name, "frames", self.total);
            0
        });
        self.progress.advance(p.frames.saturating_sub(before));
        self.frames = Some(p.frames.max(before));
        let rate = p
            .rate_hz
            .map_or("rate not measured yet".into(), |r| format!("{r:.2} Hz"));
        self.progress
            .note(&format!("{rate}, {} gaps, {:.1} s", p.gaps, p.seconds));
    }
}

pub(crate) fn run(args: &RecordArgs) -> Result<()> {
    let config = config(args)?;
    let out = config.out.clone();
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("starting the tokio runtime")?;
    let captured = runtime
        .block_on(async move {
            let shutdown = CancellationToken::new();
            tokio::spawn(super::serve::cancel_on_signal(shutdown.clone()));
            let mut shown = Shown::new(config.frames);
            let mut notice = |n: Notice<'_>| shown.notice(n);
            let done = capture::run(config, shutdown, &mut notice).await;
            super::progress::settle(shown.progress.as_mut(), done)
        })
        .map_err(|e| {
            // A full disk: the file is closed valid with the frames that fit; say what to do.
            let stopped = e.chain().any(|c| {
                matches!(
                    c.downcast_ref::<replay::WriteError>(),
                    Some(replay::WriteError::Stopped { .. })
                )
            });
            if stopped {
                e.context("recording stopped; free space or record to another disk")
            } else {
                e
            }
        })?;
    let Some(c) = captured else {
        anyhow::bail!(
            "no frames arrived; nothing written to {}: check that the source streams to this \
             host (see the lines above)",
            out.display()
        );
    };
    print_captured(&c)
}

/// The take's summary: file, frames, stream, gaps, rate, first timecode, streams left out.
fn print_captured(c: &capture::take::Captured) -> Result<()> {
    crate::out!(
        "{}: {} frames of {} ({} markers), {} of them gaps; rate {} Hz ({})",
        c.summary.path.display(),
        c.summary.frames,
        c.stream,
        c.summary.markers,
        c.gap_frames,
        c.rate_hz,
        match (c.announced_hz, c.measured_hz) {
            (Some(a), Some(m)) => format!("announced {a}, measured {m:.3}"),
            (Some(a), None) => format!("announced {a}"),
            (None, Some(m)) => format!("measured {m:.3}"),
            (None, None) => "assumed: too few frames to measure".into(),
        }
    );
    if let Some(tc) = c.first_timecode {
        crate::out!("  first timecode {tc}");
    }
    if !c.others.is_empty() {
        crate::out!(
            "  not recorded (pick one with --performer): {}",
            c.others.join(", ")
        );
    }
    Ok(())
}
