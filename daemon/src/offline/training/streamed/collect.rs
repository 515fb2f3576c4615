//! The second pass of streaming training: every frame prepared once, and everything training
//! needs from the prepared frames taken on the way, in memory bounded whatever the session's
//! length:
//!
//! - the mean and covariance of the complete frames ([`Moments`], both halves of each batch
//!   on the pool, merged in order);
//! - every prepared frame, spilled to a temporary file ([`super::spill`]) for the whitening
//!   pass (reading it back costs a fraction of reading and preparing the takes again), and
//!   the frames with gaps to fill, spilled to another;
//! - the glitch counts, the stabilisation residuals (a bounded, evenly thinned sample), each
//!   reference marker's residual;
//! - for the quality report, exactly the frames the in-memory measures read: every
//!   [`residual_stride`]-th complete frame, the kept slow-residual blocks (as their mean
//!   frame: the residual is linear), the second differences the noise estimate reads.

use anyhow::Result;
use ica_core::fit::FitData;
use ica_core::impute::{frame_gaps, FrameGaps};
use ica_core::measure::{noise_stride, residual_stride, slow_block_frames, slow_block_stride};
use ica_core::whiten::Moments;
use rayon::ThreadPool;

use super::noise::NoiseDifferences;
use super::read::{channel_arrays, PreparedTake};
use super::spill::{f32_bytes, f32_values, Spill};
use crate::offline::training::capture::RefResiduals;

/// Stabilisation residuals kept at most for their median and 95th percentile.
pub const RESIDUALS_KEPT: usize = 200_000;

/// A sample of a stream of values, thinned to every other kept value whenever it passes its
/// limit: all of a short stream, an evenly spread part of a long one.
#[derive(Debug, Clone)]
pub(super) struct Thinned {
    limit: usize,
    stride: usize,
    seen: usize,
    pub values: Vec<f64>,
}

impl Thinned {
    fn new(limit: usize) -> Self {
        Self {
            limit: limit.max(2),
            stride: 1,
            seen: 0,
            values: Vec::new(),
        }
    }

    /// Offers each of `values`, in order.
    pub(super) fn extend(&mut self, values: &[f64]) {
        values.iter().for_each(|&v| self.push(v));
    }

    fn push(&mut self, v: f64) {
        if self.seen % self.stride == 0 {
            self.values.push(v);
            if self.values.len() > self.limit {
                self.stride *= 2;
                let mut i = 0;
                self.values.retain(|_| {
                    i += 1;
                    (i - 1) % 2 == 0
                });
            }
        }
        self.seen += 1;
    }
}

/// What the pass collected (see the module docs).
#[derive(Debug)]
pub(super) struct Collected {
    /// Channels per frame.
    pub channels: usize,
    /// Moments of every frame with its mask (frames with gaps offered, not used).
    pub moments: Moments,
    /// Every prepared frame: `channels` f32 values, then one mask byte per marker.
    pub prepared: Spill,
    /// Frames with gaps to fill: `channels` f32 values, then `channels` mask bytes.
    pub gappy: Spill,
    /// Per channel, how often it is missing in the frames to fill.
    pub gap_missing: Vec<usize>,
    /// Frames left out (more than half their channels missing).
    pub left_out: usize,
    /// Samples dropped as glitches, in all and per marker.
    pub glitches: usize,
    pub glitches_per_marker: Vec<usize>,
    /// Stabilisation residuals (mm), thinned.
    pub residuals: Thinned,
    /// Second differences per channel, for the noise estimate.
    pub noise: NoiseDifferences,
    /// Complete frames at the residual stride, frame after frame.
    pub residual_frames: Vec<f32>,
    /// Mean frames of the kept slow-residual blocks.
    pub slow_means: Vec<Vec<f64>>,
    /// Frames seen so far.
    frame: usize,
    /// The residual frames' and the slow blocks' strides.
    strides: (usize, usize),
    slow_block: usize,
}

impl Collected {
    /// An empty collection for `markers` markers over takes of `take_frames` frames at
    /// `rate_hz`, spilling the prepared frames over `raw`, which the caller reads once, frame
    /// by frame ahead of them ([`Spill::overwrite`]).
    pub(super) fn new(
        markers: usize,
        take_frames: &[usize],
        rate_hz: f64,
        raw: &mut Spill,
    ) -> Result<Self> {
        let c = markers * 3;
        let total = take_frames.iter().sum();
        let slow_block = slow_block_frames(rate_hz);
        let residual = residual_stride(total);
        Ok(Self {
            channels: c,
            moments: Moments::new(c),
            prepared: raw.overwrite(c * 4 + markers)?,
            gappy: Spill::new(c * 5)?,
            gap_missing: vec![0; c],
            left_out: 0,
            glitches: 0,
            glitches_per_marker: vec![0; markers],
            residuals: Thinned::new(RESIDUALS_KEPT),
            noise: NoiseDifferences::new(c, take_frames, noise_stride(total)),
            // At its most, reserved once: pages never used are never touched.
            residual_frames: Vec::with_capacity(total.div_ceil(residual) * c),
            slow_means: Vec::new(),
            frame: 0,
            strides: (residual, slow_block_stride(total, slow_block)),
            slow_block,
        })
    }

    /// Adds a batch of prepared takes, in take order.
    ///
    /// # Errors
    /// A non-finite present sample, or the spill file failing.
    pub(super) fn add_batch(
        &mut self,
        batch: &[PreparedTake],
        refs: Option<&mut RefResiduals<'_>>,
        pool: &ThreadPool,
    ) -> Result<()> {
        let (samples, mask) = channel_arrays(batch);
        let (c, first) = (self.channels, self.frame);
        let frames = samples.len() / c.max(1);
        let mid = frames / 2;
        let half = |range: std::ops::Range<usize>| -> Result<Moments> {
            let mut m = Moments::new(c).starting_at(first + range.start);
            let data = FitData::new(&samples[range.start * c..range.end * c], c)?
                .with_missing(&mask[range.start * c..range.end * c])?;
            m.add_chunk(&data)?;
            Ok(m)
        };
        // The moments on the pool while this thread keeps the takes' books: neither reads
        // what the other writes.
        let (halves, booked) = std::thread::scope(|s| {
            let halves = s.spawn(|| pool.join(|| half(0..mid), || half(mid..frames)));
            let mut refs = refs;
            let mut at = 0;
            let booked = batch.iter().try_for_each(|take| {
                let end = at + take.frames;
                let rows = at * c..end * c;
                at = end;
                self.add_take(
                    take,
                    &samples[rows.clone()],
                    &mask[rows],
                    refs.as_deref_mut(),
                )
            });
            (halves.join(), booked)
        });
        booked?;
        let (left, right) = halves.map_err(|_| anyhow::anyhow!("the batch's moments panicked"))?;
        self.moments.merge(left?)?;
        self.moments.merge(right?)?;
        Ok(())
    }

    fn add_take(
        &mut self,
        take: &PreparedTake,
        samples: &[f32],
        mask: &[bool],
        mut refs: Option<&mut RefResiduals<'_>>,
    ) -> Result<()> {
        let (c, n) = (self.channels, self.channels / 3);
        let (res_stride, block_stride) = self.strides;
        self.glitches += take.glitches;
        take.residuals.iter().for_each(|&r| self.residuals.push(r));
        let mut block = vec![0.0f64; c];
        let (mut filled, mut index) = (0usize, 0usize);
        let mut record = Vec::new();
        let mut all = Vec::with_capacity(take.frames * (c * 4 + n));
        for f in 0..take.frames {
            let (x, m) = (&samples[f * c..(f + 1) * c], &mask[f * c..(f + 1) * c]);
            let prepared = &take.missing[f * n..(f + 1) * n];
            f32_bytes(x, &mut all);
            all.extend(prepared.iter().map(|&g| u8::from(g)));
            let raw = &take.raw_missing[f * n..(f + 1) * n];
            for (k, (&before, &after)) in raw.iter().zip(prepared).enumerate() {
                self.glitches_per_marker[k] += usize::from(!before && after);
            }
            if let Some(r) = refs.as_deref_mut() {
                r.add_frame(x, prepared);
            }
            let gaps = frame_gaps(m);
            let complete = gaps == FrameGaps::Complete;
            if complete && (self.frame + f) % res_stride == 0 {
                self.residual_frames.extend_from_slice(x);
            }
            match gaps {
                FrameGaps::Complete => {
                    block
                        .iter_mut()
                        .zip(x)
                        .for_each(|(b, &v)| *b += f64::from(v));
                    filled += 1;
                    if filled == self.slow_block {
                        if index % block_stride == 0 {
                            let scale = 1.0 / self.slow_block as f64;
                            self.slow_means
                                .push(block.iter().map(|b| b * scale).collect());
                        }
                        index += 1;
                        block.fill(0.0);
                        filled = 0;
                    }
                }
                FrameGaps::Fill => {
                    record.clear();
                    f32_bytes(x, &mut record);
                    record.extend(m.iter().map(|&g| u8::from(g)));
                    self.gappy.push(&record)?;
                    for (count, &g) in self.gap_missing.iter_mut().zip(m) {
                        *count += usize::from(g);
                    }
                }
                FrameGaps::LeaveOut => self.left_out += 1,
            }
            if !complete {
                block.fill(0.0);
                filled = 0;
            }
        }
        self.prepared.push(&all)?;
        self.noise.add_take(samples, &take.missing, take.frames);
        self.frame += take.frames;
        Ok(())
    }
}

/// Takes a batch of frames: values and the per-channel mask (frames x channels each), which it
/// may change in place.
pub(super) type FrameSink<'a> = dyn FnMut(&mut Vec<f32>, &mut Vec<bool>) -> Result<()> + 'a;

/// Reads the prepared frames back, `chunk` frames at a time, as values and a per-channel mask
/// (frames x channels each).
///
/// # Errors
/// Reading the spill file, or `each`, fails.
pub(super) fn for_each_prepared(
    prepared: &mut Spill,
    channels: usize,
    chunk: usize,
    each: &mut FrameSink<'_>,
) -> Result<()> {
    let n = channels / 3;
    let (mut values, mut mask, mut frame) = (Vec::new(), Vec::new(), Vec::new());
    prepared.for_each_chunk(chunk, &mut |bytes| {
        values.clear();
        mask.clear();
        for record in bytes.chunks_exact(4 * channels + n) {
            f32_values(&record[..4 * channels], &mut frame);
            values.extend_from_slice(&frame);
            mask.extend(record[4 * channels..].iter().flat_map(|&g| [g != 0; 3]));
        }
        each(&mut values, &mut mask)
    })
}

#[cfg(test)]
mod tests;
