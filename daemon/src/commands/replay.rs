//! `emoshift replay FILE --to HOST:PORT`: send a take over UDP exactly as a live source would.
//!
//! The schedule is [`replay::pacer::Pacer`] (absolute deadlines, labels every second, loop,
//! catch-up); this module only owns the clock, the socket and the waiting. It sleeps until
//! [`SPIN`] before a deadline and spins the rest, because a sleep alone overshoots by the
//! scheduler's slack (often 50-100 µs, more under load), and spinning a whole period would burn a
//! core for nothing.
//!
//! Frames carry the pacer's frame numbers (the take's, increasing across loops; the OSC int32
//! wraps after 2^31 frames, 207 days at 120 Hz) and capture times in take time (µs since the
//! take's first frame, plus the take's duration per loop; independent of `--speed`).
//!
//! SIGINT (Ctrl-C) and SIGTERM stop the replay between two sends and still print the summary.
//! They are caught with `tokio::signal` on a helper thread: tokio is already the daemon's
//! runtime, so this needs no extra crate, and it handles SIGTERM too.

use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr, ToSocketAddrs, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use protocol::{encode_frame_flat_into, encode_frame_into, encode_labels_into, FrameBuf, Labels};
use replay::pacer::{Action, FrameSend, Pacer, PacerOptions, PacerSummary};
use replay::Take;

use crate::cli::{ReplayArgs, WireFormat};
use crate::exit::UsageError;

/// How long before a deadline the sender stops sleeping and spins.
const SPIN: Duration = Duration::from_micros(200);
/// Longest single sleep, so a signal is noticed promptly even between sparse deadlines.
const MAX_NAP: Duration = Duration::from_millis(50);

pub(crate) fn run(args: &ReplayArgs) -> Result<()> {
    let take = crate::offline::load_take(&args.file)?;
    let to = resolve(&args.to)?;
    if take.n_markers() > protocol::MAX_FRAME_MARKERS {
        anyhow::bail!(
            "{}: {} markers do not fit one datagram (at most {})",
            args.file.display(),
            take.n_markers(),
            protocol::MAX_FRAME_MARKERS
        );
    }
    let options = PacerOptions {
        speed: args.speed,
        looping: args.looping,
        start_frame: args.start_frame,
        first_frame_number: take.first_frame,
        max_behind_frames: args.max_behind,
        ..PacerOptions::default()
    };
    let mut pacer = Pacer::new(take.rate_hz, take.n_frames(), options)
        .map_err(|e| UsageError(format!("{}: {e}", args.file.display())))?;
    let socket = UdpSocket::bind(local_for(to)).context("cannot open a udp socket")?;
    let mut sender = Sender::new(&take, args, socket, to)?;
    let stop = stop_on_signal()?;

    let origin = Instant::now();
    while !stop.load(Ordering::Relaxed) {
        match pacer.poll(origin.elapsed()) {
            Action::SendLabels => sender.send_labels(),
            Action::SendFrame(f) => sender.send_frame(&take, &f)?,
            Action::Sleep { until } => wait_until(origin + until, &stop),
            Action::Done => break,
        }
    }
    let elapsed = origin.elapsed();
    report(
        &pacer.summary(),
        &sender,
        elapsed,
        stop.load(Ordering::Relaxed),
        to,
    )
}

/// Resolves `HOST:PORT` to its first address.
fn resolve(to: &str) -> Result<SocketAddr> {
    let mut addrs = to
        .to_socket_addrs()
        .map_err(|e| UsageError(format!("--to {to:?}: {e} (expected HOST:PORT)")))?;
    addrs
        .next()
        .ok_or_else(|| UsageError(format!("--to {to:?} resolves to no address")).into())
}

/// The local address to bind for sending to `to`: loopback stays on loopback.
fn local_for(to: SocketAddr) -> SocketAddr {
    let ip = match to.ip() {
        IpAddr::V4(ip) if ip.is_loopback() => IpAddr::V4(Ipv4Addr::LOCALHOST),
        IpAddr::V4(_) => IpAddr::V4(Ipv4Addr::UNSPECIFIED),
        IpAddr::V6(ip) if ip.is_loopback() => IpAddr::V6(Ipv6Addr::LOCALHOST),
        IpAddr::V6(_) => IpAddr::V6(Ipv6Addr::UNSPECIFIED),
    };
    SocketAddr::new(ip, 0)
}

/// Sleeps until [`SPIN`] before `deadline`, then spins; returns early on a stop request.
fn wait_until(deadline: Instant, stop: &AtomicBool) {
    loop {
        let now = Instant::now();
        if now >= deadline || stop.load(Ordering::Relaxed) {
            return;
        }
        let left = deadline - now;
        if left > SPIN {
            std::thread::sleep((left - SPIN).min(MAX_NAP));
        } else {
            std::hint::spin_loop();
        }
    }
}

/// A flag raised by SIGINT or SIGTERM, watched by a helper thread with its own small runtime.
fn stop_on_signal() -> Result<Arc<AtomicBool>> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_io()
        .build()
        .context("cannot start the signal watcher")?;
    // Register the handlers before returning, so a signal right after start is not lost to the
    // default action (which would kill the process without a summary).
    #[cfg(unix)]
    let signals = {
        use tokio::signal::unix::{signal, SignalKind};
        let _guard = rt.enter();
        let int = signal(SignalKind::interrupt()).context("cannot watch SIGINT")?;
        let term = signal(SignalKind::terminate()).context("cannot watch SIGTERM")?;
        (int, term)
    };
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            rt.block_on(async move {
                #[cfg(unix)]
                {
                    let (mut int, mut term) = signals;
                    tokio::select! {
                        _ = int.recv() => {}
                        _ = term.recv() => {}
                    }
                }
                #[cfg(not(unix))]
                let _ = tokio::signal::ctrl_c().await;
            });
            flag.store(true, Ordering::Relaxed);
        })
        .context("cannot start the signal watcher")?;
    Ok(stop)
}

/// The socket and the buffers every send reuses.
struct Sender {
    socket: UdpSocket,
    to: SocketAddr,
    flat: bool,
    labels: Vec<u8>,
    frame: FrameBuf,
    datagram: Vec<u8>,
    send_errors: u64,
}

impl Sender {
    fn new(take: &Take, args: &ReplayArgs, socket: UdpSocket, to: SocketAddr) -> Result<Sender> {
        let names = Labels {
            layout_id: args.layout_id,
            names: take.labels.clone(),
        };
        let mut labels = Vec::new();
        encode_labels_into(&names, &mut labels)
            .with_context(|| format!("{}: labels cannot be sent", args.file.display()))?;
        let n = take.n_markers();
        Ok(Sender {
            socket,
            to,
            flat: args.format == WireFormat::Flat,
            labels,
            frame: FrameBuf::with_max_markers(n),
            datagram: Vec::with_capacity(protocol::frame_message_len(n) + 4 * n),
            send_errors: 0,
        })
    }

    fn send_labels(&mut self) {
        let result = self.socket.send_to(&self.labels, self.to);
        self.count(result);
    }

    fn send_frame(&mut self, take: &Take, f: &FrameSend) -> Result<()> {
        // The OSC int32 frame number wraps, as documented in the module docs.
        let number = f.frame_number as i32;
        self.frame
            .set_frame(number, f.capture_time_us, take.frame(f.index))
            .with_context(|| format!("frame index {} cannot be sent", f.index))?;
        for (m, &gone) in take.frame_missing(f.index).iter().enumerate() {
            if gone {
                self.frame.set_missing(m, true);
            }
        }
        let encoded = if self.flat {
            encode_frame_flat_into(&self.frame, &mut self.datagram)
        } else {
            encode_frame_into(&self.frame, &mut self.datagram)
        };
        encoded.with_context(|| format!("frame index {} cannot be encoded", f.index))?;
        let result = self.socket.send_to(&self.datagram, self.to);
        self.count(result);
        Ok(())
    }

    /// A failed send (a full buffer, an unreachable network) is counted and the replay goes on,
    /// as a live source would.
    fn count(&mut self, result: std::io::Result<usize>) {
        if let Err(e) = result {
            if self.send_errors == 0 {
                tracing::warn!(to = %self.to, error = %e, "send failed; counting further failures");
            }
            self.send_errors += 1;
        }
    }
}

fn report(
    s: &PacerSummary,
    sender: &Sender,
    elapsed: Duration,
    stopped: bool,
    to: SocketAddr,
) -> Result<()> {
    let how = if stopped {
        "stopped by signal after"
    } else {
        "done in"
    };
    crate::out!(
        "sent {} frames and {} label messages to {to}, {how} {:.3} s",
        s.frames_sent,
        s.labels_sent,
        elapsed.as_secs_f64()
    );
    let mean_us = match s.frames_sent {
        0 => 0,
        n => s.total_lateness.as_micros() / u128::from(n),
    };
    crate::out!(
        "late sends: {} (over {} µs), max lateness {} µs, mean {} µs, skipped {}, send errors {}",
        s.late_frames,
        replay::pacer::DEFAULT_LATE_AFTER.as_micros(),
        s.max_lateness.as_micros(),
        mean_us,
        s.skipped_frames,
        sender.send_errors
    );
    Ok(())
}
