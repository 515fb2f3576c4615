//! The demo's live part: the daemon on loopback, a client subscribed to it, a take replayed
//! into it while the emotion sweeps, and what the client saw.

use std::collections::HashMap;
use std::net::{SocketAddr, UdpSocket};
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use hdrhistogram::Histogram;
use ica_core::model::IcaModel;
use protocol::{Control, Profile};
use replay::pacer::{Pacer, PacerOptions};
use replay::Take;

use super::STREAM_S;
use crate::loopback::source::{drive, take_labels, Due, Source, SPIN};
use crate::loopback::{ControlClient, Daemon, Received, Receiver};
use crate::serve::config::RawConfig;
use crate::serve::stats::Stats;

/// What the client saw of one frame.
#[derive(Debug)]
struct Seen {
    number: i32,
    at: Instant,
    target: String,
    amount: f32,
    positions: Vec<f32>,
    missing: Vec<bool>,
}

/// The demo's client keeps what it saw (a real client would not).
fn keep(seen: &mut Vec<Seen>, r: &Received<'_>) {
    let Some((header, frame)) = r.frame else {
        return;
    };
    let state = r.state.as_ref();
    seen.push(Seen {
        number: header.frame_number,
        at: r.at,
        target: state.map_or_else(String::new, |s| s.target.to_string()),
        amount: state.map_or(0.0, |s| s.amount),
        positions: frame.positions().to_vec(),
        missing: (0..frame.marker_count())
            .map(|i| frame.is_missing(i))
            .collect(),
    });
}

/// What the sender did.
struct Sent {
    at: HashMap<i64, Instant>,
    first: Instant,
    late: u64,
}

/// The emotion state the client saw at one frame.
struct Moment {
    /// Seconds since the first send.
    t: f64,
    target: String,
    amount: f32,
    /// The received markers' coordinates on the emotion axes.
    emotion: Option<Vec<f32>>,
}

/// The live run's measurements.
pub(super) struct Live {
    sent: usize,
    received: usize,
    rate_hz: f64,
    latency_us: Histogram<u64>,
    moments: Vec<Moment>,
    late_sends: u64,
    sweep: Vec<String>,
}

pub(super) fn stream(model: &IcaModel, take: Arc<Take>, sweep: &[String]) -> Result<Live> {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("cannot start the runtime")?;
    let rate_hz = take.rate_hz;
    let (seen, sent) = runtime.block_on(serve_and_send(model, take, sweep))?;
    Ok(measure(model, &seen, &sent, sweep, rate_hz))
}

/// The daemon on loopback, a subscribed client, the take replayed into it at its rate (looped
/// for at least [`STREAM_S`] with a sweep), the emotion glided through `sweep` in equal shares.
async fn serve_and_send(
    model: &IcaModel,
    take: Arc<Take>,
    sweep: &[String],
) -> Result<(Vec<Seen>, Sent)> {
    let config = RawConfig {
        listen: Some("127.0.0.1:0".into()),
        control: Some("127.0.0.1:0".into()),
        model: Some("model.json".into()),
        ..Default::default()
    }
    .validate()?;
    let daemon = Daemon::start_with(config, model.clone()).await?;
    crate::out!(
        "daemon: frames on {}, control on {}",
        daemon.frames,
        daemon.control
    );
    let (frames_to, control_to) = (daemon.frames, daemon.control);
    let result = async {
        let control = ControlClient::new(control_to).await?;
        let client = Receiver::subscribe(&control, Profile::Compact).await?;
        crate::out!(
            "client: subscribed {} with the compact profile",
            client.addr()?
        );
        let seen = client.collect(None, Vec::new(), keep);
        let frames = take.n_frames();
        let stream_frames = (STREAM_S * take.rate_hz).ceil() as usize;
        let total = if sweep.is_empty() {
            stream_frames.min(frames)
        } else {
            stream_frames.max(frames)
        };
        let share =
            Duration::from_secs_f64(total as f64 / take.rate_hz / sweep.len().max(1) as f64);
        if let Some(first) = sweep.first() {
            control.confirm(&Control::Ramp(share.as_secs_f32())).await?;
            control.confirm(&Control::Target(first.clone())).await?;
            control.confirm(&Control::Amount(1.0)).await?;
            crate::out!(
                "sweep: towards {} in turn, {:.1} s each",
                sweep.join(", then "),
                share.as_secs_f64()
            );
        }
        let sender = tokio::task::spawn_blocking(move || send_take(&take, frames_to, total));
        for target in sweep.iter().skip(1) {
            tokio::time::sleep(share).await;
            control.confirm(&Control::Target(target.clone())).await?;
        }
        let sent = sender.await.context("the sender panicked")??;
        tokio::time::sleep(Duration::from_millis(300)).await;
        anyhow::Ok((seen.stop().await?, sent))
    }
    .await;
    // Stopped whatever happened, so a failed run leaves no daemon behind.
    daemon.stop(Duration::from_secs(2)).await?;
    result
}

/// Replays `total` frames of `take` (looping) at its rate on the pacer's deadlines.
fn send_take(take: &Take, to: SocketAddr, total: usize) -> Result<Sent> {
    let socket = UdpSocket::bind("127.0.0.1:0")?;
    let mut source = Source::new(&take_labels(take, 0), socket, to, false)?;
    let options = PacerOptions {
        first_frame_number: take.first_frame,
        looping: true,
        ..PacerOptions::default()
    };
    let mut pacer = Pacer::new(take.rate_hz, take.n_frames(), options)?;
    let mut at = HashMap::with_capacity(total);
    let first = Instant::now();
    drive(&mut pacer, SPIN, &AtomicBool::new(false), |due| {
        if let Due::Frame(f) = due {
            if f.stream_index as usize >= total {
                return Ok(false);
            }
            at.insert(f.frame_number, Instant::now());
        }
        source.send_due(take, due).map(|()| true)
    })?;
    Ok(Sent {
        at,
        first,
        late: pacer.summary().late_frames,
    })
}

/// Latencies, and the emotion coordinates of what the client received (to show the sweep in
/// model units).
fn measure(model: &IcaModel, seen: &[Seen], sent: &Sent, sweep: &[String], rate_hz: f64) -> Live {
    let mut latency_us = Stats::histogram();
    let mut processor = engine::frame::FrameProcessor::new(model);
    let mut u = vec![0.0f32; model.components()];
    let space = ica_core::model::SpaceTarget::new(model.emotion(), model.components());
    let mut moments = Vec::with_capacity(seen.len());
    for s in seen {
        if let Some(at) = sent.at.get(&i64::from(s.number)) {
            Stats::record(&mut latency_us, s.at.duration_since(*at).as_micros() as u64);
        }
        let complete = space.dims() > 0 && s.missing.len() == model.markers();
        let emotion = complete
            .then(|| processor.project(&s.positions, &s.missing, &mut u).ok())
            .flatten()
            .map(|_| {
                let mut at = vec![0.0f32; space.dims()];
                space.coordinates_into(&u, &mut at);
                at
            });
        moments.push(Moment {
            t: s.at.duration_since(sent.first).as_secs_f64(),
            target: s.target.clone(),
            amount: s.amount,
            emotion,
        });
    }
    Live {
        sent: sent.at.len(),
        received: seen.len(),
        rate_hz,
        latency_us,
        moments,
        late_sends: sent.late,
        sweep: sweep.to_vec(),
    }
}

pub(super) fn summary(
    live: &Live,
    model: &IcaModel,
    report: &Path,
    started: Instant,
) -> Result<()> {
    let lost = live.sent.saturating_sub(live.received);
    crate::out!(
        "frames: {} sent at {} Hz, {} received, {} lost ({:.2} %), {} sent late",
        live.sent,
        live.rate_hz,
        live.received,
        lost,
        100.0 * lost as f64 / live.sent.max(1) as f64,
        live.late_sends
    );
    let q = |q: f64| live.latency_us.value_at_quantile(q);
    crate::out!(
        "latency source -> daemon -> client: p50 {} us, p99 {} us, p99.9 {} us, max {} us",
        q(0.5),
        q(0.99),
        q(0.999),
        live.latency_us.max()
    );
    if !live.sweep.is_empty() {
        print_sweep(live, model)?;
    }
    crate::out!("components:");
    for (k, role) in model.roles().iter().enumerate() {
        crate::out!(
            "  c{k}: {:<9} |M_k| {:.2} mm",
            format!("{role:?}").to_lowercase(),
            model.mixing().column(k).norm()
        );
    }
    let e = model.emotion();
    for name in e.names() {
        if let Some(point) = e.point(&name) {
            let p: Vec<String> = point.iter().map(|v| format!("{v:+.3}")).collect();
            crate::out!("  emotion {name}: {}", p.join(" "));
        }
    }
    crate::out!("report: {}", report.display());
    crate::out!("demo finished in {:.1} s", started.elapsed().as_secs_f64());
    if live.received == 0 {
        bail!("the client received no frame from the daemon");
    }
    Ok(())
}

/// The sweep as the client saw it, in half-second means of the emotion coordinates.
fn print_sweep(live: &Live, model: &IcaModel) -> Result<()> {
    let space = model.emotion().axis_names();
    crate::out!(
        "emotion sweep {} as the client saw it (emotion axes {} of the received markers, 0.5 s means):",
        live.sweep.join(" -> "),
        space.join(" ")
    );
    let end = live.moments.last().map_or(0.0, |m| m.t);
    let mut t0 = 0.0;
    while t0 < end {
        let window: Vec<&Moment> = live
            .moments
            .iter()
            .filter(|m| m.t >= t0 && m.t < t0 + 0.5)
            .collect();
        let values: Vec<&Vec<f32>> = window.iter().filter_map(|m| m.emotion.as_ref()).collect();
        if let (Some(last), false) = (window.last(), values.is_empty()) {
            let mean: Vec<String> = (0..values[0].len())
                .map(|j| {
                    let m = values.iter().map(|v| v[j]).sum::<f32>() / values.len() as f32;
                    format!("{m:+.3}")
                })
                .collect();
            crate::out!(
                "  t {t0:4.1}-{:4.1} s  target {:<10} amount {:.2}  emotion {}",
                t0 + 0.5,
                last.target,
                last.amount,
                mean.join(" ")
            );
        }
        t0 += 0.5;
    }
    Ok(())
}
