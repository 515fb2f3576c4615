//! The OSC source: the frame socket's task. Datagrams from allowed senders go through the one
//! [`OscDemux`]; each frame goes to the sink, and a source whose datagram is refused hears why
//! ([`Answer`]). Every [`SWEEP_SECONDS`] the sources gone quiet are forgotten.

pub mod demux;

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use engine::pipeline::SWEEP_SECONDS;
use protocol::CaptureClock;
use tokio::net::UdpSocket;
use tokio_util::sync::CancellationToken;

pub use demux::OscDemux;

use super::{Answer, Arrival, FrameSink, InputCounters};
use crate::serve::allow::AllowList;

/// An OSC frame socket and who may send to it.
#[derive(Debug)]
pub struct OscSource {
    /// The bound frame socket.
    pub socket: UdpSocket,
    /// Senders whose datagrams are taken.
    pub allow: AllowList,
    /// Datagrams from other senders, dropped.
    pub not_allowed: Arc<AtomicU64>,
    /// Tells a source why its datagrams are refused.
    pub answer: Arc<Answer>,
    /// What the demux counts.
    pub counters: Arc<InputCounters>,
    /// Largest frame, markers.
    pub max_markers: usize,
}

/// Receives until `shutdown`: each frame of an allowed sender to `sink`, with its arrival.
pub async fn run(source: OscSource, sink: &mut FrameSink<'_>, shutdown: CancellationToken) {
    let OscSource {
        socket,
        allow,
        not_allowed,
        answer,
        counters,
        max_markers,
    } = source;
    let mut demux = OscDemux::new(max_markers, counters);
    let mut buf = vec![0u8; protocol::MAX_UDP_PAYLOAD + 1];
    let mut sweep = tokio::time::interval(Duration::from_secs(SWEEP_SECONDS));
    sweep.tick().await;
    loop {
        let (len, peer) = tokio::select! {
            () = shutdown.cancelled() => break,
            _ = sweep.tick() => {
                demux.forget_quiet_sources();
                continue;
            }
            r = socket.recv_from(&mut buf) => match r {
                Ok(r) => r,
                // ICMP errors and the like on a UDP socket: nothing to do but go on.
                Err(e) => {
                    tracing::trace!(target: "emoshift", error = %e, "frame socket receive error");
                    continue;
                }
            },
        };
        if !allow.allows(peer.ip()) {
            not_allowed.fetch_add(1, Ordering::Relaxed);
            continue;
        }
        let received = Instant::now();
        demux.handle_datagram(peer, &buf[..len], &mut |frame| {
            let arrival = Arrival {
                received,
                captured: captured_at(
                    frame.frame.header().capture_time_us,
                    frame.time.clock,
                    received,
                ),
                answer: Some(Arc::clone(&answer)),
                announced_rate_hz: None,
            };
            sink(frame, &arrival);
        });
        if let Some(refused) = demux.poll_refusal() {
            answer.tell(refused.to, &refused.why);
        }
    }
}

/// The instant on this host's clock of a capture time stamped on the UTC clock (µs since the
/// Unix epoch); `None` for a source's own clock, whose epoch is unknown.
fn captured_at(capture_us: i64, clock: CaptureClock, received: Instant) -> Option<Instant> {
    if clock != CaptureClock::Utc {
        return None;
    }
    let now_us = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .ok()?
        .as_micros() as i64;
    let ago = Duration::from_micros(u64::try_from(now_us - capture_us).ok()?);
    received.checked_sub(ago)
}
