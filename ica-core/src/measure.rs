//! The numbers behind a model's quality report ([`crate::quality`]), measured on its
//! training frames.

use std::ops::Range;

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

use crate::linalg::{cols, cols_mut, product, subtract_product};
use crate::model::IcaModel;
use crate::robust::{mad, median};
use crate::whiten::Whitener;

/// Training frames as the model saw them: positions (frames x channels, head coordinates
/// when stabilised), missing flags per channel, and each take's frame range.
#[derive(Debug, Clone, Copy)]
pub struct TrainingFrames<'a> {
    /// Positions, frames x channels (mm).
    pub samples: &'a [f32],
    /// Missing flags, frames x channels.
    pub missing: &'a [bool],
    /// Channels per frame (markers x 3).
    pub channels: usize,
    /// Frame range of each take.
    pub takes: &'a [Range<usize>],
    /// Frame rate (Hz).
    pub rate_hz: f64,
}

impl TrainingFrames<'_> {
    fn frames(&self) -> usize {
        self.missing.len() / self.channels.max(1)
    }

    fn complete(&self, f: usize) -> bool {
        !self.missing[f * self.channels..(f + 1) * self.channels]
            .iter()
            .any(|&m| m)
    }

    fn frame(&self, f: usize) -> &[f32] {
        &self.samples[f * self.channels..(f + 1) * self.channels]
    }
}

/// Frames whose residuals are computed at once: two matrix products per block instead of two
/// matrix-vector products per frame.
const RESIDUAL_BLOCK: usize = 512;

/// What a residual is measured against: the part of a frame a model reconstructs.
///
/// An [`IcaModel`] reconstructs `mean + M W (x − mean)`. The [`Whitener`] it was fitted
/// through spans the same subspace (`M W` projects onto the kept principal axes whatever the
/// rotation FastICA finds), so a streaming caller can measure the residual from the whitener
/// while FastICA runs; the two agree to rounding.
pub trait Reconstruction: Sync {
    /// Channels per frame.
    fn channels(&self) -> usize;
    /// Replaces each column of `x` (a frame, or a mean of frames: the residual is linear) by
    /// its residual.
    fn residual_columns(&self, x: &mut DMatrix<f64>);
}

fn centre_columns(x: &mut DMatrix<f64>, mean: &[f64]) {
    for mut column in x.column_iter_mut() {
        for (v, mu) in column.iter_mut().zip(mean) {
            *v -= mu;
        }
    }
}

impl Reconstruction for IcaModel {
    fn channels(&self) -> usize {
        IcaModel::channels(self)
    }

    /// `(x − mean) − M W (x − mean)`.
    fn residual_columns(&self, x: &mut DMatrix<f64>) {
        centre_columns(x, self.mean());
        let ((c, n), m) = (x.shape(), self.components());
        let mut u = vec![0.0; m * n];
        product(
            cols_mut(&mut u, m, n),
            cols(self.unmixing().as_slice(), m, c),
            cols(x.as_slice(), c, n),
        );
        subtract_product(
            cols_mut(x.as_mut_slice(), c, n),
            cols(self.mixing().as_slice(), c, m),
            cols(&u, m, n),
        );
    }
}

impl Reconstruction for Whitener {
    fn channels(&self) -> usize {
        self.mean.len()
    }

    /// `(x − mean) − E Eᵀ (x − mean)` on the live channels (`E` the kept axes), `x − mean` on
    /// the dead ones (the model's mixing has zero rows there).
    fn residual_columns(&self, x: &mut DMatrix<f64>) {
        centre_columns(x, &self.mean);
        let mut residual = x.select_rows(&self.live_channels);
        let ((nl, n), m) = (residual.shape(), self.basis.ncols());
        let mut coefficients = vec![0.0; m * n];
        product(
            cols_mut(&mut coefficients, m, n),
            cols(self.basis.as_slice(), nl, m).transpose(),
            cols(residual.as_slice(), nl, n),
        );
        subtract_product(
            cols_mut(residual.as_mut_slice(), nl, n),
            cols(self.basis.as_slice(), nl, m),
            cols(&coefficients, m, n),
        );
        for (r, &c) in self.live_channels.iter().enumerate() {
            x.row_mut(c).copy_from(&residual.row(r));
        }
    }
}

/// Frames examined at most by [`residual_by_marker`] (evenly strided).
pub const MAX_RESIDUAL_FRAMES: usize = 20_000;

/// The stride [`residual_by_marker`] reads frames at, for a session of `frames` frames.
pub fn residual_stride(frames: usize) -> usize {
    (frames / MAX_RESIDUAL_FRAMES).max(1)
}

/// Reconstruction residual per marker (mm RMS of the 3-D error) over complete training frames
/// (every [`residual_stride`]-th frame).
pub fn residual_by_marker(model: &IcaModel, data: &TrainingFrames<'_>) -> Vec<f64> {
    let stride = residual_stride(data.frames());
    let frames = (0..data.frames())
        .step_by(stride)
        .filter(|&f| data.complete(f))
        .map(|f| data.frame(f));
    residual_by_marker_of(model, frames)
}

/// [`residual_by_marker`] over the complete frames given (`channels` values each), as a
/// streaming caller collects them.
pub fn residual_by_marker_of<'a>(
    model: &IcaModel,
    frames: impl Iterator<Item = &'a [f32]>,
) -> Vec<f64> {
    ResidualSums::of(model, frames).rms()
}

/// Per marker, the squared 3-D residual summed over frames, and the frames: what
/// [`residual_by_marker_of`] averages, in parts that add (for a caller that splits the
/// frames between threads).
#[derive(Debug, Clone, PartialEq)]
pub struct ResidualSums {
    sq: Vec<f64>,
    frames: usize,
}

impl ResidualSums {
    /// The sums over the complete frames given (`channels` values each).
    pub fn of<'a>(
        model: &impl Reconstruction,
        frames: impl Iterator<Item = &'a [f32]>,
    ) -> ResidualSums {
        let c = model.channels();
        let mut sums = ResidualSums {
            sq: vec![0.0; c / 3],
            frames: 0,
        };
        let mut block: Vec<f64> = Vec::with_capacity(RESIDUAL_BLOCK * c);
        let mut add = |block: &mut Vec<f64>| {
            let mut r = DMatrix::from_vec(c, block.len() / c, std::mem::take(block));
            model.residual_columns(&mut r);
            for frame in r.column_iter() {
                for (k, s) in sums.sq.iter_mut().enumerate() {
                    *s +=
                        frame[3 * k].powi(2) + frame[3 * k + 1].powi(2) + frame[3 * k + 2].powi(2);
                }
            }
            sums.frames += r.ncols();
            *block = r.data.into();
            block.clear();
        };
        for x in frames {
            block.extend(x.iter().map(|&v| f64::from(v)));
            if block.len() == RESIDUAL_BLOCK * c {
                add(&mut block);
            }
        }
        if !block.is_empty() {
            add(&mut block);
        }
        sums
    }

    /// Adds the sums of other frames.
    pub fn add(&mut self, other: &ResidualSums) {
        for (a, b) in self.sq.iter_mut().zip(&other.sq) {
            *a += b;
        }
        self.frames += other.frames;
    }

    /// Each marker's RMS residual (mm); 0 without frames.
    pub fn rms(&self) -> Vec<f64> {
        self.sq
            .iter()
            .map(|s| (s / self.frames.max(1) as f64).sqrt())
            .collect()
    }
}

/// Window of the slow residual's low pass (seconds): expressions and moods, not speech.
pub const SLOW_WINDOW_S: f64 = 0.5;

/// Frames per block of the slow residual at `rate_hz`.
pub fn slow_block_frames(rate_hz: f64) -> usize {
    ((SLOW_WINDOW_S * rate_hz).round() as usize).max(2)
}

/// Of a take's complete blocks, every this-many-th is kept (about 4000 blocks in all).
pub fn slow_block_stride(frames: usize, block: usize) -> usize {
    (frames / block / 4000).max(1)
}

/// The strongest slow signal the model leaves out: the residual is averaged over blocks of
/// [`SLOW_WINDOW_S`] within each take (a low pass that also divides white noise by the block
/// length), and its leading direction is found by power iteration. Returns that direction's
/// RMS at its peak marker (mm) and the marker, or `None` with fewer than 8 blocks.
pub fn slow_residual(model: &IcaModel, data: &TrainingFrames<'_>) -> Option<(f64, usize)> {
    let c = data.channels;
    let block = slow_block_frames(data.rate_hz);
    let mut means: Vec<Vec<f64>> = Vec::new();
    let stride_blocks = slow_block_stride(data.frames(), block);
    for take in data.takes {
        let mut acc = vec![0.0; c];
        let mut filled = 0usize;
        let mut index = 0usize;
        for f in take.clone() {
            if !data.complete(f) {
                acc.fill(0.0);
                filled = 0;
                continue;
            }
            acc.iter_mut()
                .zip(data.frame(f))
                .for_each(|(a, &v)| *a += f64::from(v));
            filled += 1;
            if filled == block {
                if index % stride_blocks == 0 {
                    means.push(acc.iter().map(|a| a / block as f64).collect());
                }
                index += 1;
                acc.fill(0.0);
                filled = 0;
            }
        }
    }
    slow_residual_of_means(model, &means)
}

/// [`slow_residual`] from the kept blocks' mean frames (the residual is linear, so the
/// residual of a block's mean is the block's mean residual), as a streaming caller collects
/// them.
pub fn slow_residual_of_means(
    model: &impl Reconstruction,
    means: &[Vec<f64>],
) -> Option<(f64, usize)> {
    let c = model.channels();
    if means.len() < 8 {
        return None;
    }
    let mut r = DMatrix::from_iterator(c, means.len(), means.iter().flatten().copied());
    model.residual_columns(&mut r);
    slow_direction(&r)
}

/// The leading direction of the block residuals (the columns of `blocks`) at its peak marker.
fn slow_direction(blocks: &DMatrix<f64>) -> Option<(f64, usize)> {
    let (c, rows) = blocks.shape();
    if rows < 8 {
        return None;
    }
    let mean = blocks.column_mean();
    let mut centred = blocks.clone();
    for mut column in centred.column_iter_mut() {
        column -= &mean;
    }
    // The blocks' second moments (channels x channels), then power iteration on them.
    let gram = &centred * centred.transpose() / rows as f64;
    let (lambda, v) = leading_direction(&gram);
    let (marker, peak) = (0..c / 3)
        .map(|k| {
            (
                k,
                (v[3 * k].powi(2) + v[3 * k + 1].powi(2) + v[3 * k + 2].powi(2)).sqrt(),
            )
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    Some((lambda.sqrt() * peak, marker))
}

/// Largest eigenvalue of the symmetric `gram` and its unit eigenvector, by power iteration.
fn leading_direction(gram: &DMatrix<f64>) -> (f64, DVector<f64>) {
    let c = gram.ncols();
    let mut v = DVector::from_fn(c, |i, _| 1.0 + (i % 7) as f64 * 0.1);
    v.normalize_mut();
    let mut lambda = 0.0;
    let mut w = DVector::zeros(c);
    for _ in 0..200 {
        w.gemv(1.0, gram, &v, 0.0);
        let next = w.norm();
        if next <= 0.0 {
            return (0.0, v);
        }
        let converged = (next - lambda).abs() <= 1e-10 * next;
        lambda = next;
        v.copy_from(&(&w / next));
        if converged {
            break;
        }
    }
    (lambda, v)
}

/// Components whose mixing column puts at least `share` of its squared norm on one marker:
/// (component, marker, share).
pub fn one_marker_components(model: &IcaModel, share: f64) -> Vec<(usize, usize, f64)> {
    let mix = model.mixing();
    (0..model.components())
        .filter_map(|i| {
            let col = mix.column(i);
            let total = col.norm_squared();
            let (marker, top) = (0..model.markers())
                .map(|k| (k, (0..3).map(|a| col[3 * k + a].powi(2)).sum::<f64>()))
                .max_by(|a, b| a.1.total_cmp(&b.1))?;
            let s = top / total.max(1e-300);
            (s >= share).then_some((i, marker, s))
        })
        .collect()
}

/// The stride [`noise_per_coordinate`] reads second differences at, for `frames` frames.
pub fn noise_stride(frames: usize) -> usize {
    (frames / 5000).max(1)
}

/// The capture's noise per coordinate (mm): the median over channels of the robust spread of
/// second differences within takes (every [`noise_stride`]-th frame of each take, from its
/// second), divided by √6.
pub fn noise_per_coordinate(data: &TrainingFrames<'_>) -> f64 {
    let c = data.channels;
    let mut per_channel = vec![Vec::new(); c];
    let stride = noise_stride(data.frames());
    for take in data.takes {
        for f in (take.start + 1..take.end.saturating_sub(1)).step_by(stride) {
            for (ch, d2) in per_channel.iter_mut().enumerate() {
                let at = |g: usize| {
                    (!data.missing[g * c + ch]).then(|| f64::from(data.samples[g * c + ch]))
                };
                if let (Some(a), Some(b), Some(n)) = (at(f - 1), at(f), at(f + 1)) {
                    d2.push(a - 2.0 * b + n);
                }
            }
        }
    }
    noise_of_differences(&mut per_channel)
}

/// [`noise_per_coordinate`] from the second differences of each channel, as a streaming
/// caller collects them.
pub fn noise_of_differences<D: AsMut<[f64]> + Send>(per_channel: &mut [D]) -> f64 {
    // Channel by channel on the current rayon pool (collected in order).
    let mut spread: Vec<f64> = per_channel
        .par_iter_mut()
        .map(AsMut::as_mut)
        .filter(|d2| d2.len() >= 10)
        .map(|d2| mad(d2) / 6f64.sqrt())
        .collect();
    median(&mut spread)
}

#[cfg(test)]
mod tests;
