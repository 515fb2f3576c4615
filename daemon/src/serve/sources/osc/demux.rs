//! The one OSC demux, sans-IO: a datagram from a source in, its frames out as
//! [`SourceFrame`]s. `serve` and `record` both read OSC sources through it.
//!
//! Each datagram is **scanned** first ([`protocol::messages`]): bundles flattened, limits
//! enforced; a bad packet is counted by kind and dropped. `/mocap/labels` updates the source's
//! layouts ([`LayoutBook`]); `/mocap/frame` is decoded into a reusable [`FrameBuf`] and bound
//! to the source's latest labels of its marker count (the stream key is the source address
//! and that layout's id); a `/mocap/timecode` anywhere in the datagram is the frame's time.
//!
//! Call order: [`OscDemux::handle_datagram`] per datagram, then [`OscDemux::poll_refusal`];
//! [`OscDemux::forget_quiet_sources`] every [`SWEEP_SECONDS`] of the caller's clock.

use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::Arc;

use engine::pipeline::{MAX_SOURCES, QUIET_SWEEPS, SWEEP_SECONDS};
use engine::{SourceFrame, StreamKey};
use protocol::{
    decode_frame_into, decode_labels, decode_timecode, messages, Address, DecodeError,
    DecodeErrorKind, FrameBuf, FrameTime, LayoutBook, LayoutChange, Limits,
};

use crate::serve::sources::InputCounters;

/// A source's datagram refused with a reason it should hear.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refused {
    /// The source.
    pub to: SocketAddr,
    /// Why.
    pub why: String,
}

/// A layout's id and its labels, shared with the frames bound to it.
type Shared = (i32, Arc<[String]>);

/// The OSC sources' layouts and the buffers their frames are decoded into. See the module
/// docs for the call order.
#[derive(Debug)]
pub struct OscDemux {
    layouts: LayoutBook<SocketAddr>,
    /// Each layout's id and labels, shared with the frames bound to it (made when the labels
    /// change), by source and marker count as the book binds frames.
    shared: HashMap<(SocketAddr, usize), Shared>,
    limits: Limits,
    frame: FrameBuf,
    time: FrameTime,
    counters: Arc<InputCounters>,
    refusal: Option<Refused>,
    /// Per source the layout book holds, the sweep it was last heard in.
    heard: HashMap<SocketAddr, u64>,
    sweeps: u64,
}

impl OscDemux {
    /// A demux for frames of up to `max_markers` markers, counting into `counters`.
    pub fn new(max_markers: usize, counters: Arc<InputCounters>) -> OscDemux {
        OscDemux {
            layouts: LayoutBook::new(MAX_SOURCES),
            shared: HashMap::with_capacity(MAX_SOURCES),
            limits: Limits::default(),
            frame: FrameBuf::with_max_markers(max_markers),
            time: FrameTime::default(),
            counters,
            refusal: None,
            heard: HashMap::with_capacity(MAX_SOURCES),
            sweeps: 0,
        }
    }

    /// Handles one datagram from `peer`; `out` gets each frame it carries that has labels.
    pub fn handle_datagram(
        &mut self,
        peer: SocketAddr,
        datagram: &[u8],
        out: &mut dyn FnMut(&SourceFrame<'_>),
    ) {
        let msgs = match messages(datagram, &self.limits) {
            Ok(m) => m,
            Err(e) => return self.counters.bad_packet(e.kind()),
        };
        self.time = FrameTime::default();
        for msg in msgs.clone() {
            if Address::parse(msg.address) == Some(Address::Timecode) {
                match decode_timecode(msg.bytes) {
                    Ok(t) => self.time = t,
                    // The frame still goes through, without a time.
                    Err(e) => self.counters.bad_packet(e.kind()),
                }
            }
        }
        for msg in msgs {
            match Address::parse(msg.address) {
                Some(Address::Frame) => self.handle_frame(peer, msg.bytes, out),
                Some(Address::Labels) => self.handle_labels(peer, msg.bytes),
                Some(Address::Timecode) => {}
                _ => self.counters.bad_packet(DecodeErrorKind::UnknownAddress),
            }
        }
    }

    /// The refusal of the last datagram, if its source should hear why.
    pub fn poll_refusal(&mut self) -> Option<Refused> {
        self.refusal.take()
    }

    /// Forgets the sources heard last before the last [`QUIET_SWEEPS`] calls (the caller calls
    /// this every [`SWEEP_SECONDS`]): their layouts and their slot among [`MAX_SOURCES`]. A
    /// source that comes back is taken again from its next labels (sent every second).
    /// Returns the sources forgotten.
    pub fn forget_quiet_sources(&mut self) -> Vec<SocketAddr> {
        self.sweeps += 1;
        let sweeps = self.sweeps;
        let quiet: Vec<SocketAddr> = self
            .heard
            .iter()
            .filter(|&(_, &last)| last + QUIET_SWEEPS < sweeps)
            .map(|(&peer, _)| peer)
            .collect();
        for peer in &quiet {
            self.heard.remove(peer);
            self.layouts.forget(peer);
            self.shared.retain(|(p, _), _| p != peer);
        }
        quiet
    }

    fn handle_labels(&mut self, peer: SocketAddr, bytes: &[u8]) {
        match decode_labels(bytes) {
            Ok(labels) => {
                let (id, n) = (labels.layout_id, labels.names.len());
                InputCounters::add(&self.counters.labels_in);
                match self.layouts.handle_labels(&peer, labels) {
                    LayoutChange::Replaced | LayoutChange::Added => self.share(peer, id, n),
                    LayoutChange::Unchanged => {}
                    LayoutChange::Rejected => {
                        InputCounters::add(&self.counters.labels_refused);
                        let why = format!(
                            "the daemon already takes {MAX_SOURCES} sources; a source silent for {} s is forgotten, which makes room",
                            QUIET_SWEEPS * SWEEP_SECONDS
                        );
                        self.refusal = Some(Refused { to: peer, why });
                        return;
                    }
                }
                self.heard.insert(peer, self.sweeps);
            }
            Err(e @ DecodeError::DuplicateLabel { index }) => {
                // A layout whose names repeat maps no frame; the last good one stays.
                self.counters.bad_packet(e.kind());
                InputCounters::add(&self.counters.labels_refused);
                let why = format!("the marker name at argument {index} is named twice");
                self.refusal = Some(Refused { to: peer, why });
            }
            Err(e) => self.counters.bad_packet(e.kind()),
        }
    }

    /// Shares the labels of `peer`'s layout `id` of `n` markers; drops the shares of its
    /// layouts the book no longer holds.
    fn share(&mut self, peer: SocketAddr, id: i32, n: usize) {
        let OscDemux {
            layouts, shared, ..
        } = self;
        shared.retain(|(p, n), _| *p != peer || layouts.layout_for(p, *n).is_some());
        if let Some(l) = layouts.layout_for(&peer, n) {
            shared.insert((peer, n), (id, l.names.as_slice().into()));
        }
    }

    fn handle_frame(
        &mut self,
        peer: SocketAddr,
        bytes: &[u8],
        out: &mut dyn FnMut(&SourceFrame<'_>),
    ) {
        let header = match decode_frame_into(bytes, &mut self.frame) {
            Ok(h) => h,
            Err(e) => return self.counters.bad_packet(e.kind()),
        };
        InputCounters::add(&self.counters.frames_in);
        let Some((layout_id, labels)) = self.shared.get(&(peer, header.marker_count)) else {
            return InputCounters::add(&self.counters.dropped_no_layout);
        };
        // An existing key: no allocation (the map holds at most MAX_SOURCES, reserved).
        self.heard.insert(peer, self.sweeps);
        out(&SourceFrame {
            key: StreamKey {
                source: peer,
                layout_id: *layout_id,
            },
            performer: None,
            labels,
            frame: &self.frame,
            time: self.time,
        });
    }
}

#[cfg(test)]
mod tests;
