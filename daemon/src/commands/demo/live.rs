//! The demo's live part on the loopback harness: the daemon, a client subscribed to it, a take
//! replayed into it while the emotion sweeps, and what the client saw; or, with the monitor
//! page, the take looping until Ctrl-C.

use std::collections::HashMap;
use std::net::SocketAddr;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use hdrhistogram::Histogram;
use ica_core::model::{IcaModel, SpaceTarget};
use protocol::{Control, Profile};
use replay::Take;

use super::STREAM_S;
use crate::loopback::daemon::loopback_config;
use crate::loopback::source::play_take;
use crate::loopback::{ControlClient, Daemon, Received, Receiver};
use crate::serve::stats::Stats;

/// What the client saw of one frame: its number, when, the emotion state, and the received
/// markers' coordinates on the emotion axes (to show the sweep in model units).
struct Seen {
    number: i32,
    at: Instant,
    target: String,
    amount: f32,
    emotion: Option<Vec<f32>>,
}

/// The live run's measurements.
pub(super) struct Live {
    sent: HashMap<i64, Instant>,
    seen: Vec<Seen>,
    rate_hz: f64,
    late_sends: u64,
    sweep: Vec<String>,
}

/// A current-thread runtime for the demo's client side (the daemon has its own).
fn block_on<T>(work: impl std::future::Future<Output = Result<T>>) -> Result<T> {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build();
    runtime.context("cannot start the runtime")?.block_on(work)
}

/// A client of the compact profile that projects what it receives onto the emotion axes.
fn seeing(model: &IcaModel) -> impl FnMut(&mut Vec<Seen>, &Received<'_>) + Send + 'static {
    let mut processor = engine::frame::FrameProcessor::new(model);
    let (markers, mut u) = (model.markers(), vec![0.0f32; model.components()]);
    let space = SpaceTarget::new(model.emotion(), model.components());
    let mut missing = Vec::with_capacity(markers);
    move |seen, r| {
        let Some((header, frame)) = r.frame else {
            return;
        };
        missing.clear();
        missing.extend((0..frame.marker_count()).map(|i| frame.is_missing(i)));
        let complete = space.dims() > 0 && missing.len() == markers;
        let emotion = complete
            .then(|| processor.project(frame.positions(), &missing, &mut u).ok())
            .flatten()
            .map(|_| {
                let mut at = vec![0.0f32; space.dims()];
                space.coordinates_into(&u, &mut at);
                at
            });
        let state = r.state.as_ref();
        seen.push(Seen {
            number: header.frame_number,
            at: r.at,
            target: state.map_or_else(String::new, |s| s.target.to_string()),
            amount: state.map_or(0.0, |s| s.amount),
            emotion,
        });
    }
}

/// The daemon on loopback, a subscribed client, the take replayed into it at its rate (looped
/// for at least [`STREAM_S`] with a sweep), the emotion glided through `sweep` in equal shares.
pub(super) fn stream(model: &IcaModel, take: Arc<Take>, sweep: &[String]) -> Result<Live> {
    let rate_hz = take.rate_hz;
    block_on(async {
        let daemon = Daemon::start_with(loopback_config(None)?, model.clone()).await?;
        crate::out!(
            "daemon: frames on {}, control on {}",
            daemon.frames,
            daemon.control
        );
        let result = async {
            let control = ControlClient::new(daemon.control).await?;
            let client = Receiver::subscribe(&control, Profile::Compact).await?;
            crate::out!(
                "client: subscribed {} with the compact profile",
                client.addr()?
            );
            let seen = client.collect(None, Vec::new(), seeing(model));
            let frames = (STREAM_S * rate_hz).ceil() as usize;
            let total = if sweep.is_empty() {
                frames.min(take.n_frames())
            } else {
                frames.max(take.n_frames())
            };
            let share = Duration::from_secs_f64(total as f64 / rate_hz / sweep.len().max(1) as f64);
            start_sweep(&control, sweep, share).await?;
            let sender = tokio::task::spawn_blocking({
                let to = daemon.frames;
                move || send_timed(&take, to, total)
            });
            for target in sweep.iter().skip(1) {
                tokio::time::sleep(share).await;
                control.confirm(&Control::Target(target.clone())).await?;
            }
            let (sent, late_sends) = sender.await.context("the sender panicked")??;
            tokio::time::sleep(Duration::from_millis(300)).await;
            let seen = seen.stop().await?;
            Ok(Live {
                sent,
                seen,
                rate_hz,
                late_sends,
                sweep: sweep.to_vec(),
            })
        }
        .await;
        // Stopped whatever happened, so a failed run leaves no daemon behind.
        daemon.stop(Duration::from_secs(2)).await?;
        result
    })
}

/// Ramps over one `share` of the stream to the sweep's first emotion at full amount.
async fn start_sweep(control: &ControlClient, sweep: &[String], share: Duration) -> Result<()> {
    let Some(first) = sweep.first() else {
        return Ok(());
    };
    control.confirm(&Control::Ramp(share.as_secs_f32())).await?;
    control.confirm(&Control::Target(first.clone())).await?;
    control.confirm(&Control::Amount(1.0)).await?;
    let each = share.as_secs_f64();
    crate::out!(
        "sweep: towards {} in turn, {each:.1} s each",
        sweep.join(", then ")
    );
    Ok(())
}

/// Replays `total` frames of `take` to `to`: when each frame number went, and how many late.
fn send_timed(take: &Take, to: SocketAddr, total: usize) -> Result<(HashMap<i64, Instant>, u64)> {
    let mut sent = HashMap::with_capacity(total);
    let late = play_take(take, to, Some(total), &AtomicBool::new(false), |n| {
        sent.insert(n, Instant::now());
    })?;
    Ok((sent, late))
}

pub(super) fn summary(
    live: &Live,
    model: &IcaModel,
    report: &Path,
    started: Instant,
) -> Result<()> {
    let (sent, received) = (live.sent.len(), live.seen.len());
    let lost = sent.saturating_sub(received);
    let share = 100.0 * lost as f64 / sent.max(1) as f64;
    let (rate, late) = (live.rate_hz, live.late_sends);
    crate::out!("frames: {sent} sent at {rate} Hz, {received} received, {lost} lost ({share:.2} %), {late} sent late");
    let mut latency_us: Histogram<u64> = Stats::histogram();
    for s in &live.seen {
        if let Some(at) = live.sent.get(&i64::from(s.number)) {
            Stats::record(&mut latency_us, s.at.duration_since(*at).as_micros() as u64);
        }
    }
    let q = |q: f64| latency_us.value_at_quantile(q);
    let (p50, p99, p999, max) = (q(0.5), q(0.99), q(0.999), latency_us.max());
    crate::out!("latency source -> daemon -> client: p50 {p50} us, p99 {p99} us, p99.9 {p999} us, max {max} us");
    if !live.sweep.is_empty() {
        print_sweep(live, model)?;
    }
    crate::out!("components:");
    for (k, role) in model.roles().iter().enumerate() {
        let role = format!("{role:?}").to_lowercase();
        crate::out!(
            "  c{k}: {role:<9} |M_k| {:.2} mm",
            model.mixing().column(k).norm()
        );
    }
    let e = model.emotion();
    for (name, point) in e
        .names()
        .into_iter()
        .filter_map(|n| e.point(&n).map(|p| (n, p)))
    {
        let p: Vec<String> = point.iter().map(|v| format!("{v:+.3}")).collect();
        crate::out!("  emotion {name}: {}", p.join(" "));
    }
    crate::out!("report: {}", report.display());
    crate::out!("demo finished in {:.1} s", started.elapsed().as_secs_f64());
    if received == 0 {
        bail!("the client received no frame from the daemon");
    }
    Ok(())
}

/// The sweep as the client saw it, in half-second means of the emotion coordinates.
fn print_sweep(live: &Live, model: &IcaModel) -> Result<()> {
    let axes = model.emotion().axis_names().join(" ");
    let sweep = live.sweep.join(" -> ");
    crate::out!("emotion sweep {sweep} as the client saw it (emotion axes {axes} of the received markers, 0.5 s means):");
    let first = live
        .sent
        .values()
        .min()
        .copied()
        .unwrap_or_else(Instant::now);
    let t = |s: &Seen| s.at.saturating_duration_since(first).as_secs_f64();
    let end = live.seen.last().map_or(0.0, t);
    let mut t0 = 0.0;
    while t0 < end {
        let window: Vec<&Seen> = live
            .seen
            .iter()
            .filter(|s| (t0..t0 + 0.5).contains(&t(s)))
            .collect();
        let values: Vec<&Vec<f32>> = window.iter().filter_map(|s| s.emotion.as_ref()).collect();
        if let (Some(last), false) = (window.last(), values.is_empty()) {
            let mean: Vec<String> = (0..values[0].len())
                .map(|j| {
                    format!(
                        "{:+.3}",
                        values.iter().map(|v| v[j]).sum::<f32>() / values.len() as f32
                    )
                })
                .collect();
            let (target, amount) = (&last.target, last.amount);
            crate::out!(
                "  t {t0:4.1}-{:4.1} s  target {target:<10} amount {amount:.2}  emotion {}",
                t0 + 0.5,
                mean.join(" ")
            );
        }
        t0 += 0.5;
    }
    Ok(())
}

/// Serves `model` with the monitor page at `monitor` while `take` loops, until Ctrl-C; a
/// client subscribed with the compact profile renews its lease meanwhile, so the page's health
/// lists a subscriber.
pub(super) fn serve_with_monitor(model: &IcaModel, take: Arc<Take>, monitor: &str) -> Result<()> {
    block_on(async {
        let config = loopback_config(Some(monitor))
            .map_err(|e| crate::exit::UsageError(format!("--monitor: {e}")))?;
        let daemon = Daemon::start_with(config, model.clone()).await?;
        let result = async {
            let control = ControlClient::new(daemon.control).await?;
            let client = Receiver::subscribe(&control, Profile::Compact).await?;
            let received = client.collect(None, 0u64, |n, r| *n += u64::from(r.frame.is_some()));
            let (frames, control, at) = (daemon.frames, daemon.control, client.addr()?);
            crate::out!("daemon: frames on {frames}, control on {control}; a client subscribed at {at}");
            crate::out!(
                "replaying {} frames at {} Hz in a loop; open the monitor page above; Ctrl-C stops",
                take.n_frames(),
                take.rate_hz
            );
            let stop = Arc::new(AtomicBool::new(false));
            let stop2 = Arc::clone(&stop);
            let sender = tokio::task::spawn_blocking(move || play_take(&take, frames, None, &stop2, |_| {}));
            let ended = tokio::select! {
                r = tokio::signal::ctrl_c() => r.context("cannot wait for Ctrl-C"),
                r = sender => r.map_err(|e| anyhow::anyhow!("the sender panicked: {e}")).and_then(|r| r.map(drop)),
            };
            stop.store(true, Ordering::Relaxed);
            let frames = received.stop().await?;
            crate::out!("\nstopped; the client received {frames} frames");
            ended
        }
        .await;
        daemon.stop(Duration::from_secs(2)).await?;
        result
    })
}
