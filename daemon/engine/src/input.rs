//! The input port: [`SourceFrame`], the one frame every live source produces, whatever its
//! protocol. The engine ([`crate::Pipeline::handle_frame`]) and the `record` command's capture
//! both take it, so a new source is its decoder and nothing else.

use std::sync::Arc;

use protocol::{FrameBuf, FrameTime};

use crate::streams::StreamKey;

/// One frame of one stream as its source delivered it: whose, under which labels, where each
/// marker was (missing ones flagged), the source's frame number, capture time and timecode.
///
/// The labels and the performer's name are shared (`Arc`), not copied: a source makes them
/// when its layout changes (an OSC source's `/mocap/labels`, a NatNet server's model
/// definitions), and a frame can then be queued or kept without allocating.
#[derive(Debug, Clone, Copy)]
pub struct SourceFrame<'a> {
    /// The stream: the source's address and its layout id (an OSC layout, a NatNet
    /// markerset's id).
    pub key: StreamKey,
    /// The source's own name for whose markers these are (a NatNet markerset, a Motive
    /// asset); `None` when the protocol names none (OSC). Names the stream unless a configured
    /// performer owns it, and matches a performer's `markerset`.
    pub performer: Option<&'a Arc<str>>,
    /// The markers' labels, in the order of `frame`'s positions.
    pub labels: &'a Arc<[String]>,
    /// Positions in mm (missing markers flagged), the source's frame number and capture time
    /// (`frame.header()`).
    pub frame: &'a FrameBuf,
    /// The source's SMPTE timecode of the frame and the clock its capture time is on.
    pub time: FrameTime,
}

impl SourceFrame<'_> {
    /// The source's frame number.
    pub fn frame_number(&self) -> i32 {
        self.frame.header().frame_number
    }
}
