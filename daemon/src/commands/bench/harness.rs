//! The bench's harness: senders paced like a stage, receivers timing each frame, the daemon in
//! its own runtime and threads (as `emoshift serve`), and a plain relay. Only 127.0.0.1.

use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use hdrhistogram::Histogram;
use ica_core::model::IcaModel;
use protocol::{
    decode_frame_into, decode_reply, encode_control_into, encode_frame_into, messages, Control,
    FrameBuf, Reply,
};
use tokio::net::UdpSocket;
use tokio_util::sync::CancellationToken;

use super::MARKERS;
use crate::loopback::synthetic::{frame_into, labels_datagram};
use crate::serve::config::RawConfig;
use crate::serve::net::{bind_receiver, bind_receiver_std};
use crate::serve::stats::Stats;

/// What the receivers saw.
pub(super) struct Seen {
    pub(super) latency_us: Histogram<u64>,
    pub(super) received: u64,
}

/// One run through the daemon: what the receivers saw, frames sent, the daemon's `/status`.
pub(super) struct Run {
    pub(super) seen: Seen,
    pub(super) sent: u64,
    pub(super) status: Vec<(String, i64)>,
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
        self.status
            .iter()
            .find(|(k, _)| k == name)
            .map_or(-1, |(_, v)| *v)
    }
}

/// Asks the daemon for its `/status` counters.
async fn status(control: SocketAddr) -> Result<Vec<(String, i64)>> {
    let sock = UdpSocket::bind("127.0.0.1:0").await?;
    let mut out = Vec::new();
    encode_control_into(&Control::Status, &mut out);
    sock.send_to(&out, control).await?;
    let mut buf = vec![0u8; protocol::MAX_UDP_PAYLOAD];
    let n = tokio::time::timeout(Duration::from_secs(2), sock.recv(&mut buf))
        .await
        .context("no /status reply from the daemon")??;
    match decode_reply(&buf[..n])? {
        Reply::Status(pairs) => Ok(pairs),
        other => anyhow::bail!("unexpected reply to /status: {other:?}"),
    }
}

/// The daemon as `emoshift serve` runs it: its own runtime (two workers, as `serve`) and its
/// processing thread, apart from the harness's thread.
struct Daemon {
    frames: SocketAddr,
    control: SocketAddr,
    shutdown: CancellationToken,
    thread: std::thread::JoinHandle<Result<()>>,
}

impl Daemon {
    async fn start(config: crate::serve::Config, model: IcaModel) -> Result<Daemon> {
        let (tx, rx) = tokio::sync::oneshot::channel();
        let shutdown = CancellationToken::new();
        let token = shutdown.clone();
        let thread = std::thread::spawn(move || -> Result<()> {
            let runtime = tokio::runtime::Builder::new_multi_thread()
                .worker_threads(2)
                .enable_all()
                .build()?;
            runtime.block_on(async move {
                let bound = crate::serve::bind_with(config, model).await;
                let addrs = bound
                    .as_ref()
                    .map_err(|e| anyhow::anyhow!("{e:#}"))
                    .and_then(|b| Ok((b.frame_addr()?, b.control_addr()?)));
                let _ = tx.send(addrs);
                bound?.run(token).await
            })
        });
        let (frames, control) = rx.await.context("the daemon thread ended")??;
        Ok(Daemon {
            frames,
            control,
            shutdown,
            thread,
        })
    }

    async fn stop(self) -> Result<()> {
        self.shutdown.cancel();
        let thread = self.thread;
        tokio::task::spawn_blocking(move || thread.join())
            .await
            .context("joining the daemon")?
            .map_err(|_| anyhow::anyhow!("the daemon panicked"))?
    }
}

/// Paced traffic through the daemon.
pub(super) async fn through_daemon(
    model: &IcaModel,
    performers: usize,
    clients: usize,
    rate_hz: f64,
    secs: Duration,
    poll_window_us: u64,
) -> Result<Run> {
    let (receivers, addrs) = receivers(clients).await?;
    let mut raw = RawConfig {
        listen: Some("127.0.0.1:0".into()),
        control: Some("127.0.0.1:0".into()),
        model: Some("unused".into()),
        queue: Some(1024),
        poll_window_us: Some(poll_window_us),
        stats_interval_s: Some(3600.0),
        ..RawConfig::default()
    };
    raw.send = addrs.iter().map(|a| a.to_string()).collect();
    let daemon = Daemon::start(raw.validate()?, model.clone()).await?;
    let traffic = async {
        let sent = send_all(model, performers, daemon.frames, rate_hz, secs).await?;
        tokio::time::sleep(Duration::from_millis(200)).await;
        anyhow::Ok((sent, status(daemon.control).await?))
    }
    .await;
    // Stopped whatever happened, so a failed run leaves no daemon behind.
    daemon.stop().await?;
    let (sent, status) = traffic?;
    Ok(Run {
        seen: collect(receivers).await,
        sent,
        status,
    })
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

type Receivers = Vec<(tokio::task::JoinHandle<Seen>, CancellationToken)>;

async fn receivers(k: usize) -> Result<(Receivers, Vec<SocketAddr>)> {
    let mut out = Vec::with_capacity(k);
    let mut addrs = Vec::with_capacity(k);
    for _ in 0..k {
        // A client that expects bursts sizes its buffer like the daemon does.
        let sock = bind_receiver(([127, 0, 0, 1], 0).into())?;
        addrs.push(sock.local_addr()?);
        let stop = CancellationToken::new();
        let stop2 = stop.clone();
        out.push((tokio::spawn(receive(sock, stop2)), stop));
    }
    Ok((out, addrs))
}

async fn receive(sock: UdpSocket, stop: CancellationToken) -> Seen {
    let mut seen = Seen::new();
    let mut buf = vec![0u8; 65_536];
    let mut frame = FrameBuf::with_max_markers(MARKERS);
    loop {
        let n = tokio::select! {
            () = stop.cancelled() => break,
            r = sock.recv(&mut buf) => match r { Ok(n) => n, Err(_) => continue },
        };
        let now = epoch_us();
        let Ok(msgs) = messages(&buf[..n], &protocol::Limits::default()) else {
            continue;
        };
        for m in msgs {
            if let Ok(h) = decode_frame_into(m.bytes, &mut frame) {
                seen.received += 1;
                Stats::record(
                    &mut seen.latency_us,
                    now.saturating_sub(h.capture_time_us as u64),
                );
            }
        }
    }
    seen
}

async fn collect(receivers: Receivers) -> Seen {
    let mut all = Seen::new();
    for (task, stop) in receivers {
        stop.cancel();
        if let Ok(s) = task.await {
            all.add(&s);
        }
    }
    all
}

/// Microseconds since the process's bench epoch (shared by senders and receivers).
fn epoch_us() -> u64 {
    static EPOCH: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    EPOCH.get_or_init(Instant::now).elapsed().as_micros() as u64
}

/// N performers at `rate_hz` for `secs`, on absolute deadlines like a stage: one thread sends
/// every performer's frame on each tick, from its own socket (a tokio timer would bunch the
/// sends into milliseconds). It sleeps to each deadline without spinning, which would take a
/// core from the daemon on a small machine; the sleep's lateness is the stage's jitter.
/// Returns frames sent.
async fn send_all(
    model: &IcaModel,
    performers: usize,
    to: SocketAddr,
    rate_hz: f64,
    secs: Duration,
) -> Result<u64> {
    let labels = labels_datagram(model)?;
    let mut sources = Vec::with_capacity(performers);
    for p in 0..performers {
        let sock = std::net::UdpSocket::bind("127.0.0.1:0")?;
        sock.send_to(&labels, to)?;
        let mut xyz = vec![0.0f32; MARKERS * 3];
        frame_into(model, p, &mut xyz);
        sources.push((sock, xyz));
    }
    let frames = (rate_hz * secs.as_secs_f64()) as u64;
    let period = Duration::from_secs_f64(1.0 / rate_hz);
    let thread = tokio::task::spawn_blocking(move || {
        std::thread::sleep(Duration::from_millis(20));
        let start = Instant::now();
        let mut buf = FrameBuf::with_max_markers(MARKERS);
        let mut out = Vec::with_capacity(2048);
        let mut sent = 0u64;
        for n in 0..frames {
            let due = start + period.mul_f64(n as f64);
            std::thread::sleep(due.saturating_duration_since(Instant::now()));
            for (sock, xyz) in &sources {
                let t = epoch_us() as i64;
                if buf.set_frame(n as i32, t, xyz).is_ok()
                    && encode_frame_into(&buf, &mut out).is_ok()
                    && sock.send_to(&out, to).is_ok()
                {
                    sent += 1;
                }
            }
        }
        sent
    });
    thread.await.context("sender thread")
}
