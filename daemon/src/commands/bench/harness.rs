//! The bench's harness: senders paced like a stage, receivers timing each frame, the daemon in
//! its own runtime and threads (as `emoshift serve`), and a plain relay. Only 127.0.0.1.

use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use hdrhistogram::Histogram;
use ica_core::model::IcaModel;
use protocol::Labels;
use replay::pacer::{Pacer, PacerOptions};

use super::MARKERS;
use crate::loopback::source::{drive, Due, Source};
use crate::loopback::{Collecting, ControlClient, Daemon, Received, Receiver};
use crate::serve::config::RawConfig;
use crate::serve::net::bind_receiver_std;
use crate::serve::stats::Stats;
use engine::synthetic::frame_into;

/// What the receivers saw.
pub(super) struct Seen {
    pub(super) latency_us: Histogram<u64>,
    pub(super) received: u64,
}

/// One run through the daemon: what the receivers saw, frames sent, the daemon's `/status`.
pub(super) struct Run {
    pub(super) seen: Seen,
    pub(super) sent: u64,
    pub(super) status: Vec<(String, protocol::StatusValue)>,
}

impl Seen {
    pub(super) fn new() -> Seen {
        Seen {
            latency_us: Stats::histogram(),
            received: 0,
        }
    }

    pub(super) fn add(&mut self, other: &Seen) {
        self.received += other.received;
        // Same bounds on both sides, so adding never fails.
        let _ = self.latency_us.add(&other.latency_us);
    }
}

impl Run {
    /// Adds a later round; its `/status` replaces this one's.
    pub(super) fn add(&mut self, later: Run) {
        self.seen.add(&later.seen);
        self.sent += later.sent;
        self.status = later.status;
    }

    pub(super) fn get(&self, name: &str) -> i64 {
        crate::loopback::counter(&self.status, name).unwrap_or(-1)
    }
}

/// Frames sent before each measured run and not measured (numbered below zero): what a round
/// measures is the steady state, not a new daemon's first frames, nor a monitor page taking
/// its first snapshots and models.
const WARMUP: Duration = Duration::from_millis(250);

/// Warm-up frames each performer sends at `rate_hz` before the measured ones.
pub(super) fn warmup_frames(rate_hz: f64) -> usize {
    (rate_hz * WARMUP.as_secs_f64()) as usize
}

/// How long a round with the monitor waits for a page to open.
const PAGE_WAIT: Duration = Duration::from_secs(60);

/// Paced traffic through the daemon; with `monitor`, the daemon serves the monitor page there
/// and the traffic starts once a page is open.
pub(super) async fn through_daemon(
    model: &IcaModel,
    (performers, clients): (usize, usize),
    rate_hz: f64,
    secs: Duration,
    poll_window_us: u64,
    monitor: Option<&str>,
) -> Result<Run> {
    let (receivers, addrs) = receivers(clients).await?;
    let mut raw = daemon_config(&addrs, poll_window_us);
    raw.monitor = monitor.map(String::from);
    let daemon = Daemon::start_with(raw.validate()?, model.clone()).await?;
    let traffic = async {
        if monitor.is_some() {
            page_open(daemon.control).await?;
        }
        let sent = send_all(model, performers, daemon.frames, rate_hz, secs).await?;
        tokio::time::sleep(Duration::from_millis(200)).await;
        let status = ControlClient::new(daemon.control).await?.status().await?;
        anyhow::Ok((sent, status))
    }
    .await;
    // Stopped whatever happened, so a failed run leaves no daemon behind.
    daemon.stop(Duration::from_secs(5)).await?;
    let (sent, status) = traffic?;
    Ok(Run {
        seen: collect(receivers).await,
        sent,
        status,
    })
}

/// The bench daemon's config: loopback, sending to `receivers`, a long queue, quiet logs.
pub(super) fn daemon_config(receivers: &[SocketAddr], poll_window_us: u64) -> RawConfig {
    RawConfig {
        listen: Some("127.0.0.1:0".into()),
        control: Some("127.0.0.1:0".into()),
        model: Some("unused".into()),
        queue: Some(1024),
        poll_window_us: Some(poll_window_us),
        stats_interval_s: Some(3600.0),
        send: receivers.iter().map(|a| a.to_string()).collect(),
        ..RawConfig::default()
    }
}

/// The same traffic through a minimal relay: one thread, blocking receive, the same bytes
/// sent to every receiver (what `socat` does).
pub(super) async fn through_relay(
    model: &IcaModel,
    performers: usize,
    clients: usize,
    secs: Duration,
) -> Result<Seen> {
    let (receivers, addrs) = receivers(clients).await?;
    let relay = bind_receiver_std(([127, 0, 0, 1], 0).into())?;
    relay.set_read_timeout(Some(Duration::from_millis(20)))?;
    let to = relay.local_addr()?;
    let stop = Arc::new(AtomicBool::new(false));
    let stop2 = Arc::clone(&stop);
    let thread = std::thread::spawn(move || {
        let mut buf = vec![0u8; protocol::MAX_UDP_PAYLOAD];
        while !stop2.load(Ordering::Relaxed) {
            let Ok((n, _)) = relay.recv_from(&mut buf) else {
                continue;
            };
            for a in &addrs {
                let _ = relay.send_to(&buf[..n], a);
            }
        }
    });
    send_all(model, performers, to, 120.0, secs).await?;
    tokio::time::sleep(Duration::from_millis(200)).await;
    stop.store(true, Ordering::Relaxed);
    tokio::task::spawn_blocking(move || thread.join())
        .await
        .context("joining the relay")?
        .map_err(|_| anyhow::anyhow!("the relay panicked"))?;
    Ok(collect(receivers).await)
}

/// Waits until a monitor page is open on the daemon at `control` (its WebSocket connected; a
/// page reconnects by itself when a round starts a new daemon).
async fn page_open(control: SocketAddr) -> Result<()> {
    let client = ControlClient::new(control).await?;
    let start = Instant::now();
    while start.elapsed() < PAGE_WAIT {
        let status = client.status().await?;
        if crate::loopback::counter(&status, "monitor_viewers").unwrap_or(0) > 0 {
            // A moment for the page to take its first snapshots and models.
            tokio::time::sleep(Duration::from_millis(500)).await;
            return Ok(());
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    anyhow::bail!(
        "no monitor page opened within {PAGE_WAIT:?}: open the URL printed above in a browser"
    )
}

pub(super) type Receivers = Vec<Collecting<Seen>>;

pub(super) async fn receivers(k: usize) -> Result<(Receivers, Vec<SocketAddr>)> {
    let mut out = Vec::with_capacity(k);
    let mut addrs = Vec::with_capacity(k);
    for _ in 0..k {
        let receiver = Receiver::bind()?;
        addrs.push(receiver.addr()?);
        out.push(receiver.collect(None, Seen::new(), time_frame));
    }
    Ok((out, addrs))
}

/// Each frame carries its send time on the bench's clock in its capture-time field.
fn time_frame(seen: &mut Seen, r: &Received<'_>) {
    if let Some((header, _)) = r.frame.filter(|(h, _)| h.frame_number >= 0) {
        seen.received += 1;
        let now = r.at.saturating_duration_since(epoch()).as_micros() as u64;
        Stats::record(
            &mut seen.latency_us,
            now.saturating_sub(header.capture_time_us as u64),
        );
    }
}

pub(super) async fn collect(receivers: Receivers) -> Seen {
    let mut all = Seen::new();
    for r in receivers {
        if let Ok(s) = r.stop().await {
            all.add(&s);
        }
    }
    all
}

/// The bench's clock, shared by senders and receivers.
pub(super) fn epoch() -> Instant {
    static EPOCH: OnceLock<Instant> = OnceLock::new();
    *EPOCH.get_or_init(Instant::now)
}

/// N performers at `rate_hz` for `secs`, on absolute deadlines like a stage: one thread sends
/// every performer's frame on each tick, from its own socket (a tokio timer would bunch the
/// sends into milliseconds). It sleeps to each deadline without spinning, which would take a
/// core from the daemon on a small machine; the sleep's lateness is the stage's jitter.
/// Returns frames sent.
pub(super) async fn send_all(
    model: &IcaModel,
    performers: usize,
    to: SocketAddr,
    rate_hz: f64,
    secs: Duration,
) -> Result<u64> {
    let labels = Labels {
        layout_id: 0,
        names: model.labels().to_vec(),
    };
    let mut sources = Vec::with_capacity(performers);
    for p in 0..performers {
        let socket = std::net::UdpSocket::bind("127.0.0.1:0")?;
        let mut xyz = vec![0.0f32; MARKERS * 3];
        frame_into(model, p, &mut xyz);
        sources.push((Source::new(&labels, socket, to, false)?, xyz));
    }
    let frames = (rate_hz * secs.as_secs_f64()) as usize;
    let warmup = warmup_frames(rate_hz);
    // Every frame is sent, however late: the max-rate run measures where frames go missing.
    let options = PacerOptions {
        max_behind_frames: u64::MAX,
        ..PacerOptions::default()
    };
    let mut pacer = Pacer::new(rate_hz, (warmup + frames).max(1), options)?;
    let thread = tokio::task::spawn_blocking(move || {
        std::thread::sleep(Duration::from_millis(20));
        let mut sent = 0u64;
        drive(&mut pacer, Duration::ZERO, &AtomicBool::new(false), |due| {
            for (source, xyz) in &mut sources {
                match due {
                    Due::Labels => source.send_labels(),
                    Due::Frame(f) => {
                        let t = epoch().elapsed().as_micros() as i64;
                        let errors = source.send_errors;
                        // Warm-up frames are numbered below zero: the receivers skip them.
                        let number = f.stream_index as i64 - warmup as i64;
                        source.send_frame(number as i32, t, xyz, &[])?;
                        sent += u64::from(source.send_errors == errors && number >= 0);
                    }
                }
            }
            Ok(true)
        })
        .map(|()| sent)
    });
    thread.await.context("sender thread")?
}
