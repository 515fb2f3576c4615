//! The NatNet input: a NAT_FRAMEOFDATA decoded once, each markerset then down the same path
//! as an OSC `/mocap/frame` ([`super::run`]), one stream per markerset.

use core::net::SocketAddr;

use crate::engine::natnet::{NatNetFrames, NatNetLayout};
use crate::engine::streams::StreamKey;

use super::{Emitted, Pipeline};

/// The pipeline's NatNet buffers.
#[derive(Debug)]
pub(super) struct NatNetInput {
    frames: NatNetFrames,
}

impl NatNetInput {
    pub(super) fn new(max_markers: usize) -> NatNetInput {
        NatNetInput {
            frames: NatNetFrames::new(max_markers),
        }
    }
}

impl Pipeline {
    /// Handles one NAT_FRAMEOFDATA from the NatNet server at `server`, decoded with the
    /// session's `layout`: each of its markersets is the frame of one stream (key: the server
    /// and the markerset's layout id; named after the markerset unless a performer owns it).
    /// `emit` is called once per processed markerset. A datagram that does not decode is
    /// counted (`bad_natnet`) and dropped.
    pub fn handle_natnet(
        &mut self,
        server: SocketAddr,
        datagram: &[u8],
        layout: &NatNetLayout,
        emit: &mut dyn FnMut(&Emitted<'_>),
    ) {
        if self.natnet.frames.decode(datagram, layout).is_err() {
            self.counters.bad_natnet += 1;
            return;
        }
        self.time_in = self.natnet.frames.time(layout);
        for set in &layout.markersets {
            let Some(header) = self
                .natnet
                .frames
                .markerset_into(set, layout, &mut self.frame_in)
            else {
                continue;
            };
            self.counters.frames_in += 1;
            let key = StreamKey {
                source: server,
                layout_id: set.layout_id,
            };
            if self
                .streams
                .get(&key)
                .is_some_and(|s| s.source_labels() != set.labels.as_slice())
            {
                // New model definitions renamed this markerset's markers: start it over.
                self.streams.forget(server, set.layout_id);
            }
            let source = (set.labels.as_slice(), Some(set.name.as_str()));
            super::run::frame_step(super::run::step!(self), key, source, &header, emit);
        }
    }
}
