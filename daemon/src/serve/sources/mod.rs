//! The live sources, one folder per protocol: each turns its protocol into
//! [`engine::SourceFrame`]s, the one frame type the engine and the `record` command's capture
//! both read, and hands them to a [`FrameSink`] with how they arrived ([`Arrival`]). What only
//! one protocol knows stays in its folder.
//!
//! - [`osc`]: the OSC frame socket: `/mocap/labels`, `/mocap/frame`, `/mocap/timecode`;
//! - [`natnet`]: OptiTrack Motive's NatNet stream: model definitions, frames, clock offset;
//! - [`qtm`]: Qualisys QTM's RT stream: parameters, 3D frames with timecode, events.
//!
//! A new source (QTM next) is its codec in `protocol`, one folder here with a `run(config,
//! sink, shutdown)` task, and its config keys; `serve` and `record` start it like the others.

pub mod natnet;
pub mod osc;
pub mod qtm;

use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use engine::SourceFrame;
use protocol::DecodeErrorKind;

/// How a frame reached the daemon, beside what it says.
#[derive(Debug, Clone)]
pub struct Arrival {
    /// When its datagram was read off the socket.
    pub received: Instant,
    /// When it was captured, on this host's clock, where the source's clock can be placed on
    /// it (a NatNet server through its echo's clock offset, an OSC source stamping UTC);
    /// `None` otherwise.
    pub captured: Option<Instant>,
    /// Who tells the source why its frames are refused, when its protocol can hear it.
    pub answer: Option<Arc<Answer>>,
    /// The capture rate the source announced, if it does (NatNet's `FrameRate`).
    pub announced_rate_hz: Option<f64>,
}

/// Where a source's frames go: `serve`'s processing queue, or `record`'s take.
pub type FrameSink<'a> = dyn FnMut(&SourceFrame<'_>, &Arrival) + Send + 'a;

/// What a source counts before its frames reach the engine, shared with `/status` (relaxed
/// atomics: a source task and the stats reader never wait on each other).
#[derive(Debug, Default)]
pub struct InputCounters {
    /// The source's name in `/status` (`bad_<name>` counts its undecodable frames).
    pub name: &'static str,
    /// Frames decoded.
    pub frames_in: AtomicU64,
    /// Frames dropped because their source sent no labels of their size yet.
    pub dropped_no_layout: AtomicU64,
    /// Labels accepted.
    pub labels_in: AtomicU64,
    /// Labels refused (a marker named twice, too many sources); the source is told.
    pub labels_refused: AtomicU64,
    /// Frames of a binary protocol that did not decode (NatNet).
    pub bad_frames: AtomicU64,
    /// OSC datagrams that did not decode, by [`DecodeErrorKind`].
    pub bad: [AtomicU64; DecodeErrorKind::ALL.len()],
}

impl InputCounters {
    /// Counters of the source called `name`.
    pub fn named(name: &'static str) -> InputCounters {
        InputCounters {
            name,
            ..InputCounters::default()
        }
    }

    /// Counts one.
    pub fn add(counter: &AtomicU64) {
        counter.fetch_add(1, Ordering::Relaxed);
    }

    /// Counts one bad OSC packet.
    pub fn bad_packet(&self, kind: DecodeErrorKind) {
        InputCounters::add(&self.bad[kind.index()]);
    }

    /// Whether the source decodes a binary protocol whose undecodable frames it counts
    /// (`bad_<name>` in `/status`): every source but OSC, whose bad packets are counted by
    /// kind.
    pub fn bad_frames_counted(&self) -> bool {
        self.name != "osc"
    }

    /// The counts now.
    pub fn snapshot(&self) -> InputTotals {
        let get = |c: &AtomicU64| c.load(Ordering::Relaxed);
        InputTotals {
            frames_in: get(&self.frames_in),
            dropped_no_layout: get(&self.dropped_no_layout),
            labels_in: get(&self.labels_in),
            labels_refused: get(&self.labels_refused),
            bad_frames: get(&self.bad_frames),
            bad: self.bad.each_ref().map(get),
        }
    }
}

/// [`InputCounters`] read at one moment, or summed over sources.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct InputTotals {
    /// Frames decoded.
    pub frames_in: u64,
    /// Frames without labels of their size.
    pub dropped_no_layout: u64,
    /// Labels accepted.
    pub labels_in: u64,
    /// Labels refused.
    pub labels_refused: u64,
    /// Undecodable frames of a binary protocol.
    pub bad_frames: u64,
    /// Bad OSC packets by kind.
    pub bad: [u64; DecodeErrorKind::ALL.len()],
}

impl InputTotals {
    /// All bad OSC packets.
    pub fn bad_total(&self) -> u64 {
        self.bad.iter().sum()
    }

    /// `self` plus `other`.
    pub fn add(&mut self, other: &InputTotals) {
        self.frames_in += other.frames_in;
        self.dropped_no_layout += other.dropped_no_layout;
        self.labels_in += other.labels_in;
        self.labels_refused += other.labels_refused;
        self.bad_frames += other.bad_frames;
        for (a, b) in self.bad.iter_mut().zip(other.bad) {
            *a += b;
        }
    }
}

/// A source hears why its datagram was refused at most this often.
const TELL_EVERY: Duration = Duration::from_secs(1);

/// Tells an OSC source why its datagrams are refused (`/emoshift/error` from the frame
/// socket), at most once a second per source so a spoofed source cannot turn the daemon into a
/// reflector; logs it, at most one line a second however many sources.
#[derive(Debug)]
pub struct Answer {
    socket: Option<UdpSocket>,
    told: Mutex<Told>,
}

#[derive(Debug, Default)]
struct Told {
    /// When each source last heard why.
    sources: std::collections::HashMap<SocketAddr, Instant>,
    /// When a refusal was last logged, and the refusals not logged since.
    logged: (Option<Instant>, u64),
}

impl Answer {
    /// Answers from `socket` (`None`: only log).
    pub fn new(socket: Option<UdpSocket>) -> Answer {
        Answer {
            socket,
            told: Mutex::new(Told::default()),
        }
    }

    /// Tells `to` why, unless it heard a reason less than a second ago.
    pub fn tell(&self, to: SocketAddr, why: &str) {
        let now = Instant::now();
        let Ok(mut told) = self.told.lock() else {
            return;
        };
        if told
            .sources
            .get(&to)
            .is_some_and(|t| now.duration_since(*t) < TELL_EVERY)
        {
            return;
        }
        if told.sources.len() >= 256 {
            told.sources
                .retain(|_, t| now.duration_since(*t) < TELL_EVERY);
        }
        told.sources.insert(to, now);
        let (last, unlogged) = &mut told.logged;
        if last.is_none_or(|t| now.duration_since(t) >= TELL_EVERY) {
            if *unlogged > 0 {
                tracing::warn!(target: "emoshift", source = %to, %why, others = *unlogged, "datagram refused (and others not logged since the last)");
            } else {
                tracing::warn!(target: "emoshift", source = %to, %why, "datagram refused");
            }
            (*last, *unlogged) = (Some(now), 0);
        } else {
            *unlogged += 1;
        }
        drop(told);
        let Some(socket) = &self.socket else { return };
        let mut out = Vec::with_capacity(256);
        protocol::encode_error_into(protocol::address::LABELS, why, &mut out);
        let _ = socket.send_to(&out, to);
    }
}
