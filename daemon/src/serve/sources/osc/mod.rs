//! The OSC source: datagrams from allowed senders go through the one [`OscDemux`]
//! ([`OscIntake`]); each frame goes to the sink, and a source whose datagram is refused hears why
//! ([`Answer`]). Every [`SWEEP_SECONDS`] the sources gone quiet are forgotten.

pub mod demux;

use std::net::SocketAddr;
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

/// An OSC frame socket and what its datagrams become (`record`'s capture runs it as a task).
#[derive(Debug)]
pub struct OscSource {
    /// The bound frame socket.
    pub socket: UdpSocket,
    /// Who may send, and the demux.
    pub intake: OscIntake,
}

/// The OSC source without its socket: who may send, the one [`OscDemux`], and who tells a
/// refused source why. `record`'s task and `serve`'s processing thread (which reads the frame
/// socket itself) both feed it datagrams.
#[derive(Debug)]
pub struct OscIntake {
    allow: AllowList,
    not_allowed: Arc<AtomicU64>,
    answer: Arc<Answer>,
    demux: OscDemux,
}

impl OscIntake {
    /// Takes datagrams from senders `allow` lets in (counting the others in `not_allowed`),
    /// frames of up to `max_markers`, counted in `counters`; refusals told through `answer`.
    pub fn new(
        (allow, not_allowed): (AllowList, Arc<AtomicU64>),
        answer: Arc<Answer>,
        counters: Arc<InputCounters>,
        max_markers: usize,
    ) -> OscIntake {
        OscIntake {
            allow,
            not_allowed,
            answer,
            demux: OscDemux::new(max_markers, counters),
        }
    }

    /// One datagram from `peer`, read off the socket at `received`: each frame in it to
    /// `sink`; the source hears why if it is refused.
    pub fn datagram(
        &mut self,
        peer: SocketAddr,
        bytes: &[u8],
        received: Instant,
        sink: &mut FrameSink<'_>,
    ) {
        if !self.allow.allows(peer.ip()) {
            self.not_allowed.fetch_add(1, Ordering::Relaxed);
            return;
        }
        let answer = &self.answer;
        self.demux.handle_datagram(peer, bytes, &mut |frame| {
            let arrival = Arrival {
                received,
                captured: captured_at(
                    frame.frame.header().capture_time_us,
                    frame.time.clock,
                    received,
                ),
                answer: Some(Arc::clone(answer)),
                announced_rate_hz: None,
            };
            sink(frame, &arrival);
        });
        if let Some(refused) = self.demux.poll_refusal() {
            answer.tell(refused.to, &refused.why);
        }
    }

    /// Forgets the sources gone quiet (every [`SWEEP_SECONDS`]).
    pub fn forget_quiet_sources(&mut self) {
        self.demux.forget_quiet_sources();
    }
}

/// Receives until `shutdown`: each frame of an allowed sender to `sink`, with its arrival.
pub async fn run(source: OscSource, sink: &mut FrameSink<'_>, shutdown: CancellationToken) {
    let OscSource { socket, mut intake } = source;
    let mut buf = vec![0u8; protocol::MAX_UDP_PAYLOAD + 1];
    let mut sweep = tokio::time::interval(Duration::from_secs(SWEEP_SECONDS));
    sweep.tick().await;
    loop {
        let (len, peer) = tokio::select! {
            () = shutdown.cancelled() => break,
            _ = sweep.tick() => {
                intake.forget_quiet_sources();
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
        intake.datagram(peer, &buf[..len], Instant::now(), sink);
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
