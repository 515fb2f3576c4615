//! `emoshift replay FILE --to HOST:PORT`: send a take over UDP exactly as a live source would.
//!
//! The schedule is [`replay::pacer::Pacer`] (absolute deadlines, labels every second, loop,
//! catch-up); the clock, the waiting and the socket are the loopback harness's paced
//! [`Source`], which the demo, the bench and the tests send with too.
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
use replay::pacer::{Pacer, PacerOptions, PacerSummary};

use crate::cli::{ReplayArgs, WireFormat};
use crate::exit::UsageError;
use crate::loopback::source::{drive, take_labels, Source, SPIN};

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
    let labels = take_labels(&take, args.layout_id);
    let mut source = Source::new(&labels, socket, to, args.format == WireFormat::Flat)
        .with_context(|| format!("{}", args.file.display()))?;
    let stop = stop_on_signal()?;
    let origin = Instant::now();
    drive(&mut pacer, SPIN, &stop, |due| {
        source.send_due(&take, due).map(|()| true)
    })?;
    let stopped = stop.load(Ordering::Relaxed);
    report(
        &pacer.summary(),
        source.send_errors,
        origin.elapsed(),
        stopped,
        to,
    )
}

/// Resolves `HOST:PORT` to its first address.
fn resolve(to: &str) -> Result<SocketAddr> {
    let mut addrs = to
        .to_socket_addrs()
        .map_err(|e| UsageError(format!("--to {to:?}: {e} (expected HOST:PORT)")))?;
    let addr = addrs
        .next()
        .ok_or_else(|| UsageError(format!("--to {to:?} resolves to no address")))?;
    if addr.port() == 0 {
        return Err(UsageError(format!("--to {to:?}: port 0 is not a destination")).into());
    }
    Ok(addr)
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

fn report(
    s: &PacerSummary,
    send_errors: u64,
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
        send_errors
    );
    Ok(())
}
