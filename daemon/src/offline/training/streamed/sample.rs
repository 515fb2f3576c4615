//! The bounded sample streaming training learns the head and the glitch limits from: whole
//! stretches of [`SEGMENT_FRAMES`] consecutive frames, evenly spread over the session, at most
//! [`super::SAMPLE_FRAMES`] in all, drawn while the takes stream past without knowing the
//! session's exact length in advance.
//!
//! Every segment gets a running index; segments whose index is a multiple of the stride are
//! kept. When the kept frames pass the budget the stride doubles and every other kept segment
//! is dropped, so the sample stays evenly spread and within the budget. Doubling alone leaves
//! anywhere between half the budget and all of it, depending on the session's length (19,000
//! frames at 10 minutes, 13,500 at 1 and 4 hours), so a session guessed (from its files'
//! sizes) to be well over the budget starts at the stride that keeps about [`TARGET_SHARE`]
//! of it. A session within the budget is sampled whole: its takes come back exactly as they
//! were.

use crate::offline::ModelFrames;

/// Frames per sampled stretch: 2 s at 120 Hz, long enough for the speeds and second
/// differences the glitch limits and the head search read.
pub const SEGMENT_FRAMES: usize = 240;
/// Share of the budget a long session's sample aims at.
pub const TARGET_SHARE: f64 = 0.75;

/// A stretch of one take.
#[derive(Debug)]
struct Segment {
    index: usize,
    take: usize,
    start: usize,
    frames: ModelFrames,
}

/// Collects the sample (see the module docs).
#[derive(Debug)]
pub(super) struct Sampler {
    budget: usize,
    stride: usize,
    next: usize,
    kept_frames: usize,
    kept: Vec<Segment>,
}

impl Sampler {
    /// An empty sample of at most `budget` frames of a session of about `expected` frames.
    /// Only a guess over twice the budget sets the first stride, so a short session whose
    /// guess was high is still sampled whole.
    pub(super) fn new(budget: usize, expected: f64) -> Self {
        let budget = budget.max(SEGMENT_FRAMES);
        let segments = expected / SEGMENT_FRAMES as f64;
        let target = (TARGET_SHARE * budget as f64 / SEGMENT_FRAMES as f64).max(1.0);
        let stride = if expected > 2.0 * budget as f64 {
            (segments / target).floor().max(1.0) as usize
        } else {
            1
        };
        Self {
            budget,
            stride,
            next: 0,
            kept_frames: 0,
            kept: Vec::new(),
        }
    }

    /// Offers take number `take` of `total` frames; `gather` gives a range of its frames in
    /// the sample's marker order (called only for the stretches kept).
    pub(super) fn push(
        &mut self,
        take: usize,
        total: usize,
        gather: &dyn Fn(std::ops::Range<usize>) -> ModelFrames,
    ) {
        for start in (0..total).step_by(SEGMENT_FRAMES) {
            let index = self.next;
            self.next += 1;
            if index % self.stride != 0 {
                continue;
            }
            let end = (start + SEGMENT_FRAMES).min(total);
            self.kept.push(Segment {
                index,
                take,
                start,
                frames: gather(start..end),
            });
            self.kept_frames += end - start;
            while self.kept_frames > self.budget {
                self.thin();
            }
        }
    }

    /// Doubles the stride and drops the segments it no longer keeps.
    fn thin(&mut self) {
        self.stride *= 2;
        let stride = self.stride;
        self.kept.retain(|s| s.index % stride == 0);
        self.kept_frames = self.kept.iter().map(|s| s.frames.frames()).sum();
    }

    /// The sample as stretches of takes (neighbouring segments of a take joined), with its
    /// markers narrowed to `markers` (indices into the order it was collected in).
    pub(super) fn finish(self, markers: &[usize]) -> Vec<ModelFrames> {
        let mut out: Vec<ModelFrames> = Vec::new();
        let mut last: Option<(usize, usize)> = None;
        for s in self.kept {
            let narrowed = narrow(s.frames, markers);
            let end = s.start + narrowed.frames();
            match (last, out.last_mut()) {
                (Some((take, at)), Some(prev)) if take == s.take && at == s.start => {
                    prev.xyz.extend_from_slice(&narrowed.xyz);
                    prev.missing.extend_from_slice(&narrowed.missing);
                }
                _ => out.push(narrowed),
            }
            last = Some((s.take, end));
        }
        out
    }
}

/// Frames `range` of `frames`.
pub(super) fn frames_range(frames: &ModelFrames, range: std::ops::Range<usize>) -> ModelFrames {
    let n = frames.markers;
    ModelFrames {
        xyz: frames.xyz[range.start * n * 3..range.end * n * 3].to_vec(),
        missing: frames.missing[range.start * n..range.end * n].to_vec(),
        markers: n,
    }
}

/// `frames` with only `markers`, in that order: moved, not copied, when that is every marker
/// in its own order (a session whose markers are all kept).
pub(super) fn narrow(frames: ModelFrames, markers: &[usize]) -> ModelFrames {
    let n = frames.markers;
    if markers.len() == n && markers.iter().enumerate().all(|(i, &m)| i == m) {
        return frames;
    }
    let count = frames.frames();
    let mut xyz = Vec::with_capacity(count * markers.len() * 3);
    let mut missing = Vec::with_capacity(count * markers.len());
    for f in 0..count {
        for &m in markers {
            xyz.extend_from_slice(&frames.xyz[(f * n + m) * 3..(f * n + m) * 3 + 3]);
            missing.push(frames.missing[f * n + m]);
        }
    }
    ModelFrames {
        xyz,
        missing,
        markers: markers.len(),
    }
}

#[cfg(test)]
mod tests;
