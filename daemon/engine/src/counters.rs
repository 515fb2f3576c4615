//! What the engine counts: frames out, drops by reason, what the frames were like. Plain
//! integers, owned by the [`super::Pipeline`], read by the shell between frames. What a source
//! counts before a frame reaches the engine (datagrams that do not decode, frames without
//! labels) is the source's.

/// Counters of the processing path, owned by the pipeline (plain integers, no locking).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Counters {
    /// Frames processed and handed to the sink.
    pub frames_out: u64,
    /// Frames dropped because the queue was full (latest frame wins; the shell counts them).
    pub dropped_queue_full: u64,
    /// Duplicate frame numbers dropped.
    pub dropped_duplicate: u64,
    /// Frames older than the stream's last frame dropped.
    pub dropped_stale: u64,
    /// Frames of a source sharing no marker with the model, or past the stream cap.
    pub dropped_unmatched: u64,
    /// Frames the processor refused (an internal invariant; should stay 0).
    pub frame_errors: u64,
    /// Model markers missing, summed over frames.
    pub missing_markers: u64,
    /// Samples rejected as glitches, summed over frames.
    pub glitches: u64,
    /// Sources that restarted (a big backwards jump).
    pub restarts: u64,
    /// Models swapped in.
    pub model_swaps: u64,
}
