//! `emoshift demo [--keep DIR] [--real] [--monitor [IP:PORT]]`: the whole chain on an embedded
//! default, in a minute; a script over `train`'s and `analyze`'s own functions and the loopback
//! harness ([`crate::loopback`]):
//! 1. a paired synthetic session (or, with `--real`, the bundled Facial-Sing capture);
//! 2. train and 3. analyse a model (progress and summaries as `train` and `analyze` print them);
//! 4. the daemon on loopback in this process, a client subscribed with the compact profile, a
//!    neutral take replayed into it at its rate while the emotion sweeps through named emotions;
//! 5. a summary: frames, loss, latency, the sweep as the client saw it, the components, the report.
//!
//! With `--monitor [IP:PORT]`, steps 4 and 5 become the daemon serving the monitor page with the
//! take looping until Ctrl-C (or SIGTERM, as `serve` stops).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use ica_core::model::IcaModel;
use protocol::Profile;
use replay::synth::{write_session, SynthParams};
use replay::Take;

use super::analyze::{analyze_and_write, Report};
use crate::cli::DemoArgs;
use crate::loopback::daemon::loopback_config;
use crate::loopback::probe::{emotion_probe, latency_us, windows, Seen};
use crate::loopback::scripted::{sweep, Replayed};
use crate::loopback::{block_on, Received, Subscribed};

/// The bundled real capture (NaturalPoint ARENA, 38 markers at 100 Hz; see
/// replay/tests/fixtures/SOURCE.md) and the regions read off its geometry.
const FACIAL_SING: &[u8] = include_bytes!("../../../replay/tests/fixtures/Facial-Sing.c3d");
const FACIAL_SING_REGIONS: &str = include_str!("../../tests/fixtures/facial-sing.regions.toml");
const FACIAL_SING_MANIFEST: &str =
    "rate_hz = 100\n\n[[take]]\nfile = \"Facial-Sing.c3d\"\nsentence = \"song\"\nemotion = \"singing\"\n";

/// Sentences of the demo session: 8 x 4 emotions over 2 emotion directions, about 13,000
/// frames at 120 Hz.
const SENTENCES: usize = 8;
/// Seconds of live streaming (the take loops).
const STREAM_S: f64 = 12.0;

pub(crate) fn run(args: &DemoArgs) -> Result<()> {
    let started = Instant::now();
    let Some(dir) = &args.keep else {
        let dir = tempfile::Builder::new()
            .prefix("emoshift-demo-")
            .tempdir()
            .context("cannot create a temporary folder")?
            .keep();
        let result = chain(args, &dir, started);
        // Only the report stays, so the path in the summary opens; the rest was scaffolding.
        for entry in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
            if entry.file_name() != "report" {
                let path = entry.path();
                let _ = std::fs::remove_dir_all(&path).or_else(|_| std::fs::remove_file(&path));
            }
        }
        if result.is_ok() {
            crate::out!(
                "(session and model were temporary; `emoshift demo --keep DIR` keeps them)"
            );
        }
        return result;
    };
    crate::offline::output::check_out_dir(dir, false)?;
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    chain(args, dir, started)
}

fn chain(args: &DemoArgs, dir: &Path, started: Instant) -> Result<()> {
    let (manifest, regions, take, emotions) = if args.real {
        crate::out!("\n== 1/5 the bundled real capture (Facial-Sing, 38 markers at 100 Hz)");
        real_session(dir)?
    } else {
        crate::out!("\n== 1/5 a paired synthetic session (8 sentences x neutral, happy, sad, angry over 2 emotion directions)");
        synthetic_session(dir, args.seed)?
    };
    crate::out!("\n== 2/5 training the ICA model");
    let model_path = dir.join("model.json");
    super::train::train_session(&manifest, regions.as_deref(), &model_path)?;
    crate::out!("\n== 3/5 analysing the components");
    let report = Report {
        dir: &dir.join("report"),
        write_model: true,
        axes: crate::offline::analysis::Axes::default(),
    };
    let (model, _) = analyze_and_write(&model_path, &manifest, regions.as_deref(), &report)?;
    let take = Arc::new(crate::offline::load_take(&take)?);
    if let Some(addr) = &args.monitor {
        crate::out!("\n== 4/5 serving on loopback with the monitor page, the take looping");
        return serve_with_monitor(&model, take, addr);
    }
    crate::out!("\n== 4/5 serving on loopback and replaying a take through it");
    let (replayed, seen) = stream(&model, take, &emotions)?;
    crate::out!("\n== 5/5 summary");
    summary(&replayed, &seen, &model, &emotions)?;
    crate::out!("report: {}", report.dir.join("report.html").display());
    crate::out!("demo finished in {:.1} s", started.elapsed().as_secs_f64());
    if seen.is_empty() {
        bail!("the client received no frame from the daemon");
    }
    Ok(())
}

/// The inputs of training and analysis (manifest, regions file), the take to stream, and the
/// emotions to sweep through while streaming (none without emotion pairs).
type Session = (PathBuf, Option<PathBuf>, PathBuf, Vec<String>);

fn synthetic_session(dir: &Path, seed: u64) -> Result<Session> {
    let names = |list: &[&str]| list.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let params = SynthParams {
        seed,
        sentences: SENTENCES,
        emotions: names(&["neutral", "happy", "sad", "angry"]),
        emotion_dims: 2,
        ..SynthParams::default()
    };
    let s = dir.join("session");
    let summary = write_session(&s, &params, replay::Format::C3d)
        .with_context(|| format!("cannot write the session to {}", s.display()))?;
    let (takes, frames, markers) = (summary.takes.len(), summary.total_frames, summary.markers);
    crate::out!(
        "wrote {takes} takes, {frames} frames, {markers} markers to {}",
        s.display()
    );
    let take = s.join("s01_neutral.c3d");
    Ok((
        summary.manifest,
        None,
        take,
        names(&["sad", "happy", "angry"]),
    ))
}

fn real_session(dir: &Path) -> Result<Session> {
    let take = dir.join("Facial-Sing.c3d");
    let (regions, manifest) = (dir.join("regions.toml"), dir.join("session.toml"));
    for (path, bytes) in [
        (&take, FACIAL_SING),
        (&regions, FACIAL_SING_REGIONS.as_bytes()),
        (&manifest, FACIAL_SING_MANIFEST.as_bytes()),
    ] {
        std::fs::write(path, bytes).with_context(|| format!("cannot write {}", path.display()))?;
    }
    let what = "its regions and a one-take manifest (no emotion pairs)";
    crate::out!("wrote {}, {what}", take.display());
    Ok((manifest, Some(regions), take, Vec::new()))
}

/// The daemon on loopback and a subscribed client; the take replayed into it at its rate
/// (looped for at least [`STREAM_S`] with a sweep) while the emotion glides through `emotions`
/// in equal shares; what was sent and what the client saw.
fn stream(model: &IcaModel, take: Arc<Take>, emotions: &[String]) -> Result<(Replayed, Vec<Seen>)> {
    let frames = (STREAM_S * take.rate_hz).ceil() as usize;
    let total = match emotions {
        [] => frames.min(take.n_frames()),
        _ => frames.max(take.n_frames()),
    };
    let share = total as f64 / take.rate_hz / emotions.len().max(1) as f64;
    let (config, model2) = (loopback_config(None)?, model.clone());
    let run = Subscribed::run(config, model2, Profile::Compact, async |live| {
        let (d, client) = (&live.daemon, live.client.addr()?);
        crate::out!("daemon: frames on {}, control on {}", d.frames, d.control);
        crate::out!("client: subscribed {client} with the compact profile");
        if !emotions.is_empty() {
            let each = emotions.join(", then ");
            crate::out!("sweep: towards {each} in turn, {share:.1} s each");
        }
        let seen = live.client.collect(None, Vec::new(), emotion_probe(model));
        let script = sweep(emotions, Duration::from_secs_f64(share));
        let replayed = live.replay(take, total, &script).await;
        Ok((replayed?, seen.stop().await?))
    });
    block_on(run)
}

fn summary(replayed: &Replayed, seen: &[Seen], model: &IcaModel, names: &[String]) -> Result<()> {
    let (sent, received, late) = (replayed.sent.len(), seen.len(), replayed.late_sends);
    let lost = sent.saturating_sub(received);
    let share = 100.0 * lost as f64 / sent.max(1) as f64;
    let rate = replayed.rate_hz;
    crate::out!("frames: {sent} sent at {rate} Hz, {received} received, {lost} lost ({share:.2} %), {late} sent late");
    let latency = latency_us(&replayed.sent, seen);
    let q = |q: f64| latency.value_at_quantile(q);
    let (p50, p99, p999, max) = (q(0.5), q(0.99), q(0.999), latency.max());
    crate::out!("latency source -> daemon -> client: p50 {p50} us, p99 {p99} us, p99.9 {p999} us, max {max} us");
    if !names.is_empty() {
        let axes = model.emotion().axis_names().join(" ");
        let sweep = names.join(" -> ");
        crate::out!("emotion sweep {sweep} as the client saw it (emotion axes {axes} of the received markers, 0.5 s means):");
        let first = replayed.sent.values().min().copied();
        for w in windows(seen, first.unwrap_or_else(Instant::now), 0.5) {
            let (t0, t1, target, amount) = (w.from_s, w.from_s + 0.5, &w.target, w.amount);
            let mean = signed(&w.emotion);
            crate::out!(
                "  t {t0:4.1}-{t1:4.1} s  target {target:<10} amount {amount:.2}  emotion {mean}"
            );
        }
    }
    crate::out!("components:");
    for (k, role) in model.roles().iter().enumerate() {
        let role = format!("{role:?}").to_lowercase();
        let norm = model.mixing().column(k).norm();
        crate::out!("  c{k}: {role:<9} |M_k| {norm:.2} mm");
    }
    let e = model.emotion();
    for name in e.names() {
        if let Some(point) = e.point(&name) {
            crate::out!("  emotion {name}: {}", signed(point));
        }
    }
    Ok(())
}

/// `+0.123 -0.456`.
fn signed<T: std::fmt::Display>(values: impl IntoIterator<Item = T>) -> String {
    let text: Vec<String> = values.into_iter().map(|v| format!("{v:+.3}")).collect();
    text.join(" ")
}

/// Serves `model` with the monitor page at `monitor` while `take` loops, until Ctrl-C or
/// SIGTERM; a client subscribed with the compact profile renews its lease meanwhile, so the
/// page's health lists a subscriber.
fn serve_with_monitor(model: &IcaModel, take: Arc<Take>, monitor: &str) -> Result<()> {
    let config = loopback_config(Some(monitor))
        .map_err(|e| crate::exit::UsageError(format!("--monitor: {e}")))?;
    let run = Subscribed::run(config, model.clone(), Profile::Compact, async |live| {
        let count = |n: &mut u64, r: &Received<'_>| *n += u64::from(r.frame.is_some());
        let received = live.client.collect(None, 0, count);
        let (frames, control, at) = (live.daemon.frames, live.daemon.control, live.client.addr()?);
        crate::out!(
            "daemon: frames on {frames}, control on {control}; a client subscribed at {at}"
        );
        let (n, rate) = (take.n_frames(), take.rate_hz);
        crate::out!("replaying {n} frames at {rate} Hz in a loop; open the monitor page above; Ctrl-C stops");
        let ended = live.loop_until(take, super::serve::signalled()).await;
        let received = received.stop().await?;
        crate::out!("\nstopped; the client received {received} frames");
        ended
    });
    block_on(run)
}
