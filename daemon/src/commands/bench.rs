//! `emoshift bench`: the daemon against a plain UDP relay on loopback, in one run.
//!
//! 1. Paced: N senders at 120 Hz, K receivers, through the daemon and through a minimal relay
//!    (receive, send the same bytes to every receiver), alternating in rounds of a second.
//!    Each frame carries its send time in the capture-time field, which the daemon keeps, so a
//!    receiver measures the whole path. The daemon's `/status` tells its own stage latencies.
//! 2. Max rate: one sender at 50,000 frames/s through the daemon to one receiver: loss, and
//!    where frames went (from `/status`).
//! 3. One processing thread: frames through [`Pipeline`] back to back (109 markers, m = 20).
//!
//! Bounded in time, only 127.0.0.1.

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

use crate::cli::BenchArgs;
use crate::serve::config::RawConfig;
use crate::serve::net::{bind_receiver, bind_receiver_std};
use crate::serve::pipeline::{Pipeline, PipelineConfig};
use crate::serve::stats::Stats;
use crate::serve::synthetic::{frame_into, labels_datagram, random_model};

const MARKERS: usize = 109;
const COMPONENTS: usize = 20;
const MAX_RATE_HZ: f64 = 50_000.0;
/// The daemon and the relay alternate in rounds of at most this long, so that a change in
/// the machine's load during the run falls on both alike.
const ROUND: Duration = Duration::from_secs(1);

/// What the receivers saw.
struct Seen {
    latency_us: Histogram<u64>,
    received: u64,
}

/// One run through the daemon: what the receivers saw, frames sent, the daemon's `/status`.
struct Run {
    seen: Seen,
    sent: u64,
    status: Vec<(String, i64)>,
}

impl Seen {
    fn new() -> Seen {
        Seen {
            latency_us: Stats::histogram(),
            received: 0,
        }
    }

    fn add(&mut self, other: &Seen) {
        self.received += other.received;
        // Same bounds on both sides, so adding never fails.
        let _ = self.latency_us.add(&other.latency_us);
    }
}

impl Run {
    /// Adds a later round; its `/status` replaces this one's.
    fn add(&mut self, later: Run) {
        self.seen.add(&later.seen);
        self.sent += later.sent;
        self.status = later.status;
    }

    fn get(&self, name: &str) -> i64 {
        self.status
            .iter()
            .find(|(k, _)| k == name)
            .map_or(-1, |(_, v)| *v)
    }
}

pub(crate) fn run(args: &BenchArgs) -> Result<()> {
    if args.performers == 0 || args.clients == 0 || !(args.seconds > 0.0 && args.seconds <= 60.0) {
        return Err(crate::exit::UsageError(
            "--performers and --clients must be at least 1, --seconds in (0, 60]".into(),
        )
        .into());
    }
    let model = random_model(MARKERS, COMPONENTS, 1);
    // Senders and receivers on one thread; the daemon and the relay each on their own.
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("starting the tokio runtime")?;
    let rounds = (args.seconds / ROUND.as_secs_f64()).ceil().max(1.0) as u32;
    let per_round = Duration::from_secs_f64(args.seconds) / rounds;
    let (n, k) = (args.performers, args.clients);
    let (daemon, relay, max) = runtime.block_on(async {
        let w = args.poll_window_us;
        let mut daemon = through_daemon(&model, n, k, 120.0, per_round, w).await?;
        let mut relay = through_relay(&model, n, k, per_round).await?;
        for _ in 1..rounds {
            daemon.add(through_daemon(&model, n, k, 120.0, per_round, w).await?);
            relay.add(&through_relay(&model, n, k, per_round).await?);
        }
        let max = through_daemon(&model, 1, 1, MAX_RATE_HZ, Duration::from_secs(1), w).await?;
        anyhow::Ok((daemon, relay, max))
    })?;
    let sent = daemon.sent * k as u64;
    crate::out!(
        "paced: {} performers x 120 Hz, {} clients, {} s, {MARKERS} markers, m = {COMPONENTS}",
        args.performers,
        args.clients,
        args.seconds
    );
    for (name, s) in [("daemon", &daemon.seen), ("relay", &relay)] {
        crate::out!("  {name}: {} of ~{sent} datagrams received", s.received);
    }
    crate::out!(
        "  inside the daemon: received -> processed p50 {} µs, p99 {} µs; processed -> sent p50 {} µs, p99 {} µs",
        daemon.get("processed_p50_us"),
        daemon.get("processed_p99_us"),
        daemon.get("sent_p50_us"),
        daemon.get("sent_p99_us"),
    );
    crate::out!(
        "  frames caught by polling around the beat: {} of {} windows",
        daemon.get("poll_hits"),
        daemon.get("poll_hits") + daemon.get("poll_misses"),
    );
    for (label, q) in [("p50", 0.5), ("p99", 0.99), ("p99.9", 0.999), ("max", 1.0)] {
        let d = daemon.seen.latency_us.value_at_quantile(q);
        let r = relay.latency_us.value_at_quantile(q);
        crate::out!(
            "{label} added latency: {d} µs (relay {r} µs, ratio {:.2}x)",
            d as f64 / r.max(1) as f64
        );
    }
    print_max_rate(&max)?;
    let (per_frame_us, fps) = processing_rate(&model)?;
    crate::out!(
        "processing: {per_frame_us:.2} µs/frame median over batches, {fps:.0} frames/s on one thread"
    );
    Ok(())
}

/// Where the frames of the max-rate run went, stage by stage.
fn print_max_rate(max: &Run) -> Result<()> {
    let received = max.seen.received as i64;
    let frames_in = max.get("frames_in");
    crate::out!(
        "max rate: {} frames sent at {MAX_RATE_HZ} /s, {received} received, loss {:.3}%",
        max.sent,
        100.0 * (1.0 - received as f64 / max.sent.max(1) as f64)
    );
    crate::out!(
        "  lost at the daemon's socket {}, dropped in the daemon {} (queue full {}, stale {}), \
         not sent {}, lost at the receiver's socket {}",
        max.sent as i64 - frames_in,
        frames_in - max.get("frames_out"),
        max.get("frames_dropped"),
        max.get("dropped_stale"),
        max.get("dropped_send_buffer") + max.get("send_errors"),
        max.get("datagrams_sent") - received,
    );
    Ok(())
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
async fn through_daemon(
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
    let sent = send_all(model, performers, daemon.frames, rate_hz, secs).await?;
    tokio::time::sleep(Duration::from_millis(200)).await;
    let status = status(daemon.control).await?;
    daemon.stop().await?;
    Ok(Run {
        seen: collect(receivers).await,
        sent,
        status,
    })
}

/// The same traffic through a minimal relay: one thread, blocking receive, the same bytes
/// sent to every receiver (what `socat` does).
async fn through_relay(
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
/// every performer's frame on each tick, from its own socket, sleeping then spinning the last
/// moments like `emoshift replay` (a tokio timer would bunch the sends into milliseconds).
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

/// Frames through one [`Pipeline`] back to back: median µs/frame over batches, frames/s.
fn processing_rate(model: &IcaModel) -> Result<(f64, f64)> {
    let model = Arc::new(model.clone());
    let mut pipeline = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
    let peer: SocketAddr = "127.0.0.1:9".parse()?;
    let mut d = labels_datagram(&model)?;
    pipeline.handle_datagram(peer, &d, &mut |_| {});
    let mut xyz = vec![0.0f32; MARKERS * 3];
    frame_into(&model, 3, &mut xyz);
    let mut buf = FrameBuf::with_max_markers(MARKERS);
    buf.set_frame(0, 0, &xyz)?;
    encode_frame_into(&buf, &mut d)?;
    let (batch, batches) = (2_000usize, 25usize);
    let mut per_frame = Vec::with_capacity(batches);
    let mut n: i32 = 0;
    let start = Instant::now();
    for _ in 0..batches {
        let t = Instant::now();
        for _ in 0..batch {
            n += 1;
            // frame number: after "/mocap/frame\0..." (16) and ",ihbb\0\0\0" (8)
            d[24..28].copy_from_slice(&n.to_be_bytes());
            pipeline.handle_datagram(peer, &d, &mut |_| {});
        }
        per_frame.push(t.elapsed().as_secs_f64() * 1e6 / batch as f64);
    }
    let total = start.elapsed().as_secs_f64();
    per_frame.sort_by(f64::total_cmp);
    if pipeline.counters.frames_out != (batch * batches) as u64 {
        anyhow::bail!(
            "the pipeline dropped frames: {} of {} out",
            pipeline.counters.frames_out,
            batch * batches
        );
    }
    Ok((per_frame[batches / 2], (batch * batches) as f64 / total))
}
