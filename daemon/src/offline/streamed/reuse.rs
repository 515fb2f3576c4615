//! A first pass's projections, kept for the second (issue 35).
//!
//! `edit --to-emotion` reads a take twice: once for its mean components, once to edit it.
//! One processor sees the same frames in the same order both times, so every frame's
//! preparation (glitch checks, head pose) and projection come out the same; the second pass
//! redid them, a third of a 1-hour edit's CPU. The first pass now keeps them, up to a budget
//! of memory, with the processor's state after the last frame kept. The second takes them
//! back and carries on from that state at the first frame it has none for, so the output is
//! the same to the bit whatever the budget. When every frame was kept and the second pass
//! needs nothing else of the take ([`super::FrameSink::reads_frames`]), it does not read the
//! take again at all ([`replay_pass`]).

use anyhow::Result;
use engine::frame::{FrameProcessor, Prepared};

use super::{Frame, FrameSink};
use crate::offline::progress::Progress;

/// Memory a first pass keeps for the second, by default: 83 minutes at 120 Hz and 20 components
/// (224 bytes a frame); a longer take is prepared and projected again after that.
pub const KEEP_BYTES: usize = 128 << 20;

/// Frames' projections kept, in order from the take's first frame.
pub(crate) struct Kept {
    prepared: Vec<Prepared>,
    /// `components` values a frame.
    u: Vec<f32>,
    components: usize,
    /// Most frames kept.
    limit: usize,
    /// Frames offered, kept or not.
    seen: usize,
    /// The processor's state after the last frame kept, once the budget is full.
    resume: Option<FrameProcessor>,
}

impl Kept {
    /// Room for what `bytes` of memory holds of frames of `components` components (`bytes`
    /// 0 keeps nothing), at most `frames` when the take's length is known.
    pub(crate) fn new(bytes: usize, components: usize, frames: Option<usize>) -> Kept {
        let per_frame = std::mem::size_of::<Prepared>() + components * std::mem::size_of::<f32>();
        let limit = bytes / per_frame;
        // A header's count may lie: reserve for it only within the budget, and only if the
        // memory is there (else the vectors grow with the frames actually read).
        let reserve = frames.map_or(0, |n| n.min(limit));
        let (mut prepared, mut u) = (Vec::new(), Vec::new());
        if prepared.try_reserve_exact(reserve).is_err()
            || u.try_reserve_exact(reserve * components).is_err()
        {
            (prepared, u) = (Vec::new(), Vec::new());
        }
        Kept {
            prepared,
            u,
            components,
            limit,
            seen: 0,
            resume: None,
        }
    }

    /// Keeps a frame's projection while there is room; `processor` has just made it.
    fn keep(&mut self, prepared: Prepared, u: &[f32], processor: &FrameProcessor) {
        self.seen += 1;
        if self.prepared.len() == self.limit {
            return;
        }
        if self.prepared.len() == self.prepared.capacity() {
            // Grown by doubling as a Vec does, but never past the budget (a take whose length
            // its header does not give).
            let more = self
                .prepared
                .len()
                .max(64)
                .min(self.limit - self.prepared.len());
            self.prepared.reserve_exact(more);
            self.u.reserve_exact(more * self.components);
        }
        self.prepared.push(prepared);
        self.u.extend_from_slice(&u[..self.components]);
        if self.prepared.len() == self.limit {
            self.resume = Some(processor.clone());
        }
    }

    /// Frame `index`'s projection into `u`, when it was kept.
    fn take_back(&self, index: usize, u: &mut [f32]) -> Option<Prepared> {
        let prepared = *self.prepared.get(index)?;
        let m = self.components;
        u[..m].copy_from_slice(&self.u[index * m..(index + 1) * m]);
        Some(prepared)
    }

    /// Whether every frame the first pass saw was kept.
    pub(crate) fn is_whole(&self) -> bool {
        self.prepared.len() == self.seen
    }
}

/// A pass over the frames of a take `kept` holds whole, without reading it: each frame's kept
/// projection to `sink`, which must not read frames ([`FrameSink::reads_frames`]), in blocks
/// of `block_frames`, until the sink is past the next; `markers` in the model. Reports
/// progress as step `name`; returns the frames seen.
pub(crate) fn replay_pass(
    kept: &Kept,
    (markers, block_frames): (usize, usize),
    (progress, name): (&mut dyn Progress, &str),
    sink: &mut dyn FrameSink,
) -> Result<usize> {
    debug_assert!(kept.is_whole() && !sink.reads_frames());
    let frames = kept.prepared.len();
    progress.step(name, "frames", Some(frames as u64));
    let none_missing = vec![false; markers];
    let mut u = vec![0.0f32; kept.components];
    let mut index = 0;
    while index < frames {
        let end = frames.min(index + block_frames.max(1));
        for i in index..end {
            let Some(prepared) = kept.take_back(i, &mut u) else {
                break;
            };
            let frame = Frame {
                index: i,
                source: (&[], &[]),
                model: (&[], &none_missing),
                prepared,
                u: &mut u,
            };
            sink.frame(frame)?;
        }
        sink.end_block()?;
        progress.advance((end - index) as u64);
        index = end;
        if sink.is_past(index) {
            break;
        }
    }
    Ok(index)
}

/// What a pass does with [`Kept`] projections.
pub(crate) enum Reuse<'a> {
    /// Neither keeps nor takes back.
    Off,
    /// Keeps each frame's projection while there is room (the first pass).
    Keep(&'a mut Kept),
    /// Takes back the projections kept, and projects the frames after them (the second).
    TakeBack(&'a Kept),
}

impl Reuse<'_> {
    /// The processor a pass starts with: a new one, or the state the first pass reached after
    /// its last frame kept.
    pub(crate) fn processor(&self, new: impl FnOnce() -> FrameProcessor) -> FrameProcessor {
        match self {
            Reuse::TakeBack(Kept {
                resume: Some(state),
                ..
            }) => state.clone(),
            _ => new(),
        }
    }

    /// Frame `index`'s projection into `u`, when it was kept and this pass takes it back.
    pub(crate) fn take_back(&self, index: usize, u: &mut [f32]) -> Option<Prepared> {
        match self {
            Reuse::TakeBack(kept) => kept.take_back(index, u),
            _ => None,
        }
    }

    /// Keeps a frame's projection, when this pass keeps them.
    pub(crate) fn keep(&mut self, prepared: Prepared, u: &[f32], processor: &FrameProcessor) {
        if let Reuse::Keep(kept) = self {
            kept.keep(prepared, u, processor);
        }
    }
}
