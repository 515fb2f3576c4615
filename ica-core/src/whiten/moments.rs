//! Streaming mean and covariance of the used frames, chunk by chunk, mergeable.
//!
//! # Numerics
//! Each accumulator keeps `(n, mean, M2)` with `M2 = Σ (x - mean)(x - mean)ᵀ` in f64. A chunk is
//! centred on the running mean (on the first used frame at the start), so a large common offset
//! (a marker 10 m from the origin) never enters a sum; its frames are added by the blocked syrk
//! kernel, then `(mean, M2)` are moved to the new mean with one rank-1 update
//! (`M2 -= n δδᵀ`, `δ = Σ (x - mean) / n`, small since the running mean is already close).
//! Two accumulators merge with Chan, Golub & LeVeque's pairwise formula
//! `M2 = M2a + M2b + δδᵀ na nb / n`: every term is positive semi-definite, nothing cancels.
//!
//! # Which frames count
//! As in [`super::whiten`]: a frame with any missing sample is left out, except that a channel
//! missing in *every* frame is dead rather than excluding everything. Streaming cannot know
//! "every frame" in advance, so each accumulator keeps the set `I` of channels missing in every
//! frame it has seen, and the moments of exactly the frames whose missing set equals `I`. A frame
//! whose missing set shrinks `I` proves the frames counted so far were not complete after all:
//! they are dropped. Merging intersects the sets the same way. At the end `I` is the set of
//! channels missing everywhere and the moments are those of the used frames, with no per-frame
//! memory. Call [`Moments::frame_is_used`] in a later pass to recognise a used frame.

use nalgebra::DMatrix;

use super::kernels::{all_finite, centre_into};
use super::stats::frame_is_used;
use super::syrk::{accumulate_upper, rank_one_upper};
use crate::input::{FitData, FitError};

/// Used frames centred per syrk call: 128 x 327 f64 (335 KB) stays in L2; 128 beat 256 and
/// 512 by 3 and 17 % (see benches/stream.rs).
const BLOCK_FRAMES: usize = 128;

/// Streaming per-channel mean and covariance of the used frames (see the module docs).
///
/// Fold chunks with [`Moments::add_chunk`]; fold partial accumulators built on other threads
/// with [`Moments::merge`]. For bit-identical results run to run, cut the frames into the same
/// chunks and merge the partials in the same order (chunk order), whatever the thread count.
///
/// ```
/// use ica_core::fit::FitData;
/// use ica_core::whiten::Moments;
/// let frames = [1.0f32, 10.0, 2.0, 20.0, 3.0, 60.0];
/// let (mut a, mut b) = (Moments::new(2), Moments::new(2).starting_at(2));
/// a.add_chunk(&FitData::new(&frames[..4], 2)?)?;
/// b.add_chunk(&FitData::new(&frames[4..], 2)?)?;
/// a.merge(b)?;
/// assert_eq!(a.frames_used(), 3);
/// assert_eq!(a.mean(), &[2.0, 30.0]);
/// assert_eq!(a.covariance()[(0, 1)], 25.0);
/// # Ok::<(), ica_core::FitError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Moments {
    channels: usize,
    /// Index of this accumulator's first frame in the whole session (for error messages).
    first_frame: usize,
    frames_total: usize,
    /// Whether any frame was offered (before that, `missing_everywhere` means nothing).
    seen_any: bool,
    /// Channels missing in every frame seen so far.
    missing_everywhere: Vec<bool>,
    frames_used: usize,
    /// Mean of the used frames (0 on channels in `missing_everywhere`).
    mean: Vec<f64>,
    /// Upper triangle of `Σ (x - mean)(x - mean)ᵀ` (the lower one is stale).
    m2: DMatrix<f64>,
    /// Scratch: centred used frames, `channels x BLOCK_FRAMES`, one frame per column.
    block: Vec<f64>,
    /// Scratch: `Σ (x - mean)` over the frames of the current chunk.
    shift: Vec<f64>,
    /// Scratch: channels missing in every frame of the current chunk.
    chunk_missing: Vec<bool>,
}

impl Moments {
    /// An empty accumulator for frames of `channels` values.
    pub fn new(channels: usize) -> Self {
        Self {
            channels,
            first_frame: 0,
            frames_total: 0,
            seen_any: false,
            missing_everywhere: vec![false; channels],
            frames_used: 0,
            mean: vec![0.0; channels],
            m2: DMatrix::zeros(channels, channels),
            block: Vec::new(),
            shift: vec![0.0; channels],
            chunk_missing: vec![false; channels],
        }
    }

    /// Numbers this accumulator's frames from `first_frame` in errors (a partial over a later
    /// part of the session names the bad frame by its index in the session).
    pub fn starting_at(mut self, first_frame: usize) -> Self {
        self.first_frame = first_frame;
        self
    }

    /// Channels per frame.
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// Frames offered so far.
    pub fn frames_total(&self) -> usize {
        self.frames_total
    }

    /// Frames counted in the moments so far (see the module docs: this can drop when a later
    /// frame shows that an earlier "missing everywhere" channel was seen after all).
    pub fn frames_used(&self) -> usize {
        self.frames_used
    }

    /// Per-channel mean of the used frames (0 for channels missing everywhere).
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }

    /// Channels missing in every frame so far (all `false` before any frame).
    pub fn missing_everywhere(&self) -> &[bool] {
        &self.missing_everywhere
    }

    /// Whether a frame with these missing flags counts, given the frames seen so far (once
    /// every frame was added: whether it is one of the used frames).
    pub fn frame_is_used(&self, missing: Option<&[bool]>) -> bool {
        !self.seen_any || frame_is_used(&self.missing_everywhere, missing)
    }

    /// Unbiased covariance of every channel, `channels x channels` (divided by `used - 1`; rows
    /// and columns of channels missing everywhere are 0).
    pub fn covariance(&self) -> DMatrix<f64> {
        let all: Vec<usize> = (0..self.channels).collect();
        self.covariance_of(&all)
    }

    /// The unbiased covariance restricted to `channels` (ascending indices).
    pub(crate) fn covariance_of(&self, channels: &[usize]) -> DMatrix<f64> {
        let dof = (self.frames_used.max(2) - 1) as f64;
        DMatrix::from_fn(channels.len(), channels.len(), |i, j| {
            let (a, b) = (channels[i].min(channels[j]), channels[i].max(channels[j]));
            self.m2[(a, b)] / dof
        })
    }

    /// Adds a chunk of frames.
    ///
    /// # Errors
    /// [`FitError::ChannelMismatch`] for a chunk of another width; [`FitError::NonFinite`] for a
    /// present sample that is NaN or infinite (frame counted from [`Moments::starting_at`]).
    /// Nothing is added on error.
    pub fn add_chunk<T: Copy + Into<f64>>(
        &mut self,
        chunk: &FitData<'_, T>,
    ) -> Result<(), FitError> {
        if chunk.channels() != self.channels {
            return Err(FitError::ChannelMismatch {
                expected: self.channels,
                got: chunk.channels(),
            });
        }
        self.scan(chunk)?;
        self.frames_total += chunk.frames();
        if chunk.frames() == 0 {
            return Ok(());
        }
        self.intersect_missing();
        // Taken out for the loop (no allocation), put back below.
        let set = std::mem::take(&mut self.missing_everywhere);
        let added = self.add_used(chunk, &set);
        self.missing_everywhere = set;
        self.recentre(added);
        Ok(())
    }

    /// Adds the frames of `chunk` whose missing set is `set`; returns how many.
    fn add_used<T: Copy + Into<f64>>(&mut self, chunk: &FitData<'_, T>, set: &[bool]) -> usize {
        let dead = set.contains(&true).then_some(set);
        let p = self.channels;
        self.block.resize(p * BLOCK_FRAMES, 0.0);
        let (mut filled, mut added) = (0, 0);
        for f in 0..chunk.frames() {
            let used = match chunk.frame_missing(f) {
                None => dead.is_none(),
                flags => frame_is_used(set, flags),
            };
            if !used {
                continue;
            }
            if self.frames_used == 0 && added == 0 {
                // The first used frame is the first reference: offsets cancel exactly.
                for (c, (m, &v)) in self.mean.iter_mut().zip(chunk.frame(f)).enumerate() {
                    *m = if dead.is_some_and(|d| d[c]) {
                        0.0
                    } else {
                        v.into()
                    };
                }
            }
            let col = &mut self.block[filled * p..(filled + 1) * p];
            centre_into(col, chunk.frame(f), dead, &self.mean);
            filled += 1;
            added += 1;
            if filled == BLOCK_FRAMES {
                self.flush(filled);
                filled = 0;
            }
        }
        if filled > 0 {
            self.flush(filled);
        }
        added
    }

    /// Adds `other`'s frames (Chan et al.'s pairwise merge). `other`'s frames are taken to come
    /// after this accumulator's.
    ///
    /// # Errors
    /// [`FitError::ChannelMismatch`] if the two accumulators have different widths.
    pub fn merge(&mut self, other: Moments) -> Result<(), FitError> {
        if other.channels != self.channels {
            return Err(FitError::ChannelMismatch {
                expected: self.channels,
                got: other.channels,
            });
        }
        self.frames_total += other.frames_total;
        if !other.seen_any {
            return Ok(());
        }
        let theirs = &other.missing_everywhere;
        let set: Vec<bool> = if self.seen_any {
            let ours = &self.missing_everywhere;
            ours.iter().zip(theirs).map(|(&a, &b)| a && b).collect()
        } else {
            theirs.clone()
        };
        if self.seen_any && self.missing_everywhere != set {
            self.reset();
        }
        let keep_theirs = *theirs == set && other.frames_used > 0;
        self.missing_everywhere = set;
        self.seen_any = true;
        if !keep_theirs {
            return Ok(());
        }
        if self.frames_used == 0 {
            self.frames_used = other.frames_used;
            self.mean = other.mean;
            self.m2 = other.m2;
            return Ok(());
        }
        let (na, nb) = (self.frames_used as f64, other.frames_used as f64);
        let n = na + nb;
        for (d, (a, b)) in self.shift.iter_mut().zip(self.mean.iter().zip(&other.mean)) {
            *d = b - a;
        }
        self.m2 += &other.m2;
        rank_one_upper(&mut self.m2, &self.shift, na * nb / n);
        for (a, d) in self.mean.iter_mut().zip(&self.shift) {
            *a += d * nb / n;
        }
        self.shift.fill(0.0);
        self.frames_used += other.frames_used;
        Ok(())
    }

    /// Adds `filled`'s used frames without counting its frames as offered: they are frames this
    /// accumulator was already offered with gaps (and so did not use), now with the gaps
    /// filled ([`crate::impute::GapModel`]). The result is the moments of the session with its
    /// gaps filled, as [`super::whiten`] sees it after [`crate::impute::fill_gaps`].
    ///
    /// # Errors
    /// As [`Moments::merge`].
    pub fn merge_filled(&mut self, filled: Moments) -> Result<(), FitError> {
        let offered = self.frames_total;
        self.merge(filled)?;
        self.frames_total = offered;
        Ok(())
    }

    /// Checks every present sample is finite and records, in `chunk_missing`, the channels
    /// missing in every frame of the chunk.
    fn scan<T: Copy + Into<f64>>(&mut self, chunk: &FitData<'_, T>) -> Result<(), FitError> {
        let p = self.channels;
        let bad = |f: usize, c: usize, value: f64| FitError::NonFinite {
            frame: self.first_frame + self.frames_total + f,
            channel: c,
            value,
        };
        if !chunk.has_mask() {
            self.chunk_missing.fill(false);
            if !all_finite(chunk.samples()) {
                let at = chunk
                    .samples()
                    .iter()
                    .position(|&v| !v.into().is_finite())
                    .expect("a non-finite sample was seen");
                return Err(bad(at / p, at % p, chunk.samples()[at].into()));
            }
            return Ok(());
        }
        self.chunk_missing.fill(true);
        for f in 0..chunk.frames() {
            let flags = chunk.frame_missing(f).expect("the chunk has a mask");
            for (c, (&v, &miss)) in chunk.frame(f).iter().zip(flags).enumerate() {
                if !miss {
                    let value: f64 = v.into();
                    if !value.is_finite() {
                        return Err(bad(f, c, value));
                    }
                }
                self.chunk_missing[c] &= miss;
            }
        }
        Ok(())
    }

    /// Intersects the running missing-everywhere set with the chunk's, dropping the frames
    /// counted so far if it shrank.
    fn intersect_missing(&mut self) {
        if self.seen_any {
            for (c, &a) in self.chunk_missing.iter_mut().zip(&self.missing_everywhere) {
                *c &= a;
            }
            if self.chunk_missing != self.missing_everywhere {
                self.reset();
            }
        }
        std::mem::swap(&mut self.missing_everywhere, &mut self.chunk_missing);
        self.seen_any = true;
    }

    /// Forgets every frame counted (not the frames offered).
    fn reset(&mut self) {
        self.frames_used = 0;
        self.mean.fill(0.0);
        self.m2.fill(0.0);
        self.shift.fill(0.0);
    }

    /// Adds the first `filled` centred frames of `block` to the shift and `M2`.
    fn flush(&mut self, filled: usize) {
        let p = self.channels;
        let data = &self.block[..p * filled];
        for col in data.chunks_exact(p) {
            for (s, &v) in self.shift.iter_mut().zip(col) {
                *s += v;
            }
        }
        accumulate_upper(&mut self.m2, data);
    }

    /// Moves `(mean, M2)` from the old mean to the mean including the `added` new frames.
    fn recentre(&mut self, added: usize) {
        if added == 0 {
            return;
        }
        self.frames_used += added;
        let n = self.frames_used as f64;
        self.shift.iter_mut().for_each(|s| *s /= n);
        rank_one_upper(&mut self.m2, &self.shift, -n);
        for (m, d) in self.mean.iter_mut().zip(&self.shift) {
            *m += d;
        }
        self.shift.fill(0.0);
    }
}
