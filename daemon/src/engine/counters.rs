//! What the engine counts: frames in and out, drops by reason, bad packets by kind. Plain
//! integers, owned by the [`super::Pipeline`], read by the shell between frames.

use protocol::DecodeErrorKind;

/// Counters of the processing path, owned by the pipeline (plain integers, no locking).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Counters {
    /// Frame messages received.
    pub frames_in: u64,
    /// Frames processed and encoded.
    pub frames_out: u64,
    /// Frames dropped because the queue was full (latest frame wins).
    pub dropped_queue_full: u64,
    /// Duplicate frame numbers dropped.
    pub dropped_duplicate: u64,
    /// Frames older than the stream's last frame dropped.
    pub dropped_stale: u64,
    /// Frames without labels of their size from their source yet.
    pub dropped_no_layout: u64,
    /// Frames of a source sharing no marker with the model, or past the stream cap.
    pub dropped_unmatched: u64,
    /// Frames the processor refused (an internal invariant; should stay 0).
    pub frame_errors: u64,
    /// Labels messages accepted.
    pub labels_in: u64,
    /// Labels messages refused (a marker named twice); the source is told.
    pub labels_refused: u64,
    /// Model markers missing, summed over frames.
    pub missing_markers: u64,
    /// Samples rejected as glitches, summed over frames.
    pub glitches: u64,
    /// Sources that restarted (a big backwards jump).
    pub restarts: u64,
    /// Models swapped in.
    pub model_swaps: u64,
    /// NatNet frames that did not decode.
    pub bad_natnet: u64,
    /// Bad packets by [`DecodeErrorKind`].
    pub bad: [u64; DecodeErrorKind::ALL.len()],
}

impl Counters {
    /// Counts one bad packet.
    pub fn bad_packet(&mut self, kind: DecodeErrorKind) {
        self.bad[kind.index()] += 1;
    }

    /// All bad packets.
    pub fn bad_total(&self) -> u64 {
        self.bad.iter().sum()
    }
}
