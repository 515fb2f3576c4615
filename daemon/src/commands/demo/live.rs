//! The demo's live part on the loopback harness: the daemon, a client subscribed to it, a take
//! replayed into it while the emotion sweeps, and what the client saw; or, with the monitor
//! page, the take looping until Ctrl-C.

use std::collections::HashMap;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use ica_core::model::IcaModel;
use protocol::{Control, Profile};
use replay::Take;

use super::STREAM_S;
use crate::loopback::daemon::loopback_config;
use crate::loopback::probe::{emotion_probe, latency_us, windows, Seen};
use crate::loopback::source::{play_take, play_take_timed};
use crate::loopback::{block_on, ControlClient, Daemon, Receiver};

/// The live run's measurements.
pub(super) struct Live {
    sent: HashMap<i64, Instant>,
    seen: Vec<Seen>,
    rate_hz: f64,
    late_sends: u64,
    sweep: Vec<String>,
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
            let seen = client.collect(None, Vec::new(), emotion_probe(model));
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
                move || play_take_timed(&take, to, total)
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
    let latency = latency_us(&live.sent, &live.seen);
    let q = |q: f64| latency.value_at_quantile(q);
    let (p50, p99, p999, max) = (q(0.5), q(0.99), q(0.999), latency.max());
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
    let first = live.sent.values().min().copied();
    for w in windows(&live.seen, first.unwrap_or_else(Instant::now), 0.5) {
        let mean: Vec<String> = w.emotion.iter().map(|v| format!("{v:+.3}")).collect();
        let (t0, target, amount) = (w.from_s, &w.target, w.amount);
        crate::out!(
            "  t {t0:4.1}-{:4.1} s  target {target:<10} amount {amount:.2}  emotion {}",
            t0 + 0.5,
            mean.join(" ")
        );
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
