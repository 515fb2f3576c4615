//! The numbers behind a model's quality report ([`crate::quality`]), measured on its
//! training frames.

use std::ops::Range;

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

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
        let u = self.unmixing() * &*x;
        x.gemm(-1.0, self.mixing(), &u, 1.0);
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
        let live = x.select_rows(&self.live_channels);
        let coefficients = self.basis.tr_mul(&live);
        let mut residual = live;
        residual.gemm(-1.0, &self.basis, &coefficients, 1.0);
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
pub fn noise_of_differences(per_channel: &mut [Vec<f64>]) -> f64 {
    // Channel by channel on the current rayon pool (collected in order).
    let mut spread: Vec<f64> = per_channel
        .par_iter_mut()
        .filter(|d2| d2.len() >= 10)
        .map(|d2| mad(d2) / 6f64.sqrt())
        .collect();
    median(&mut spread)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::tests::{labels, report};

    /// A little LCG: the test's numbers without a dependency.
    fn numbers(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    /// 5 markers, 3 components, a random mixing and mean.
    fn model() -> IcaModel {
        let mut r = numbers(7);
        let mixing = DMatrix::from_fn(15, 3, |_, _| r());
        let mean = (0..15).map(|_| 100.0 * r()).collect();
        IcaModel::new(labels(5), 120.0, mean, mixing, report(15, 3)).expect("valid parts")
    }

    /// `(x − mean) − M W (x − mean)` of one frame, by matrix-vector products.
    fn residual_of(model: &IcaModel, x: &[f64]) -> DVector<f64> {
        let centred =
            DVector::from_iterator(x.len(), x.iter().zip(model.mean()).map(|(x, m)| x - m));
        let u = model.unmixing() * &centred;
        centred - model.mixing() * u
    }

    #[test]
    fn residuals_in_blocks_are_the_residuals_of_each_frame() {
        let model = model();
        let mut r = numbers(11);
        // More than two blocks, the last one partial.
        let frames: Vec<Vec<f32>> = (0..2 * RESIDUAL_BLOCK + 37)
            .map(|_| (0..15).map(|_| (100.0 * r()) as f32).collect())
            .collect();
        let mut sq = [0.0; 5];
        for x in &frames {
            let x: Vec<f64> = x.iter().map(|&v| f64::from(v)).collect();
            let res = residual_of(&model, &x);
            for (k, s) in sq.iter_mut().enumerate() {
                *s += (0..3).map(|a| res[3 * k + a].powi(2)).sum::<f64>();
            }
        }
        let got = residual_by_marker_of(&model, frames.iter().map(Vec::as_slice));
        // In two parts that add, as a caller splitting the frames between threads sums them.
        let (a, b) = frames.split_at(RESIDUAL_BLOCK + 5);
        let mut parts = ResidualSums::of(&model, a.iter().map(Vec::as_slice));
        parts.add(&ResidualSums::of(&model, b.iter().map(Vec::as_slice)));
        for (k, (x, y)) in got.iter().zip(parts.rms()).enumerate() {
            assert!(
                (x - y).abs() <= 1e-12 * x,
                "marker {k}: {x} vs {y} in parts"
            );
        }
        for (k, s) in sq.iter().enumerate() {
            let want = (s / frames.len() as f64).sqrt();
            assert!(want > 1.0, "the residual is not trivial");
            assert!(
                (got[k] - want).abs() <= 1e-9 * want,
                "marker {k}: {} vs {want}",
                got[k]
            );
        }
    }

    #[test]
    fn the_whitening_measures_the_residual_of_any_model_fitted_through_it() {
        use crate::fit::FitData;
        use crate::whiten::{Components, Moments};
        let mut r = numbers(5);
        // 5 markers; channel 4 never moves while training (a dead channel).
        let frame = |r: &mut dyn FnMut() -> f64, dead: f32| -> Vec<f32> {
            (0..15)
                .map(|c| if c == 4 { dead } else { (100.0 * r()) as f32 })
                .collect()
        };
        let training: Vec<f32> = (0..600).flat_map(|_| frame(&mut r, 12.5)).collect();
        let mut moments = Moments::new(15);
        moments
            .add_chunk(&FitData::new(&training, 15).expect("15 channels"))
            .expect("finite");
        let w = Whitener::from_moments(&moments, Components::Fixed(3)).expect("a whitening");
        assert_eq!(w.dead_channels, vec![4]);
        // A model through it, as FastICA makes one: M = E Λ^½ Rᵀ on the live rows.
        let rotation = nalgebra::Rotation3::from_euler_angles(0.3, -1.1, 2.0);
        let rotation = DMatrix::from_fn(3, 3, |i, j| rotation[(i, j)]);
        let scaled = DMatrix::from_fn(14, 3, |i, j| w.basis[(i, j)] * w.eigenvalues[j].sqrt());
        let live = scaled * rotation.transpose();
        let mut mixing = DMatrix::zeros(15, 3);
        for (row, &c) in w.live_channels.iter().enumerate() {
            mixing.row_mut(c).copy_from(&live.row(row));
        }
        let model = IcaModel::new(labels(5), 120.0, w.mean.clone(), mixing, report(15, 3))
            .expect("valid parts");
        // Other frames, the dead channel moving too.
        let frames: Vec<Vec<f32>> = (0..700)
            .map(|i| frame(&mut r, 12.5 + (i % 7) as f32))
            .collect();
        let by_model = residual_by_marker_of(&model, frames.iter().map(Vec::as_slice));
        let by_whitening = ResidualSums::of(&w, frames.iter().map(Vec::as_slice)).rms();
        for (k, (a, b)) in by_model.iter().zip(&by_whitening).enumerate() {
            assert!(*a > 1.0, "marker {k}: the residual is not trivial");
            assert!((a - b).abs() <= 1e-9 * a, "marker {k}: {a} vs {b}");
        }
        let means: Vec<Vec<f64>> = frames
            .chunks(50)
            .map(|block| {
                (0..15)
                    .map(|c| block.iter().map(|f| f64::from(f[c])).sum::<f64>() / 50.0)
                    .collect()
            })
            .collect();
        let (a, at_a) = slow_residual_of_means(&model, &means).expect("14 blocks");
        let (b, at_b) = slow_residual_of_means(&w, &means).expect("14 blocks");
        assert_eq!(at_a, at_b);
        assert!((a - b).abs() <= 1e-9 * a, "slow residual {a} vs {b}");
    }

    #[test]
    fn the_slow_residual_is_the_leading_direction_of_the_block_residuals() {
        let model = model();
        let mut r = numbers(3);
        // Block means along one slow direction plus a little noise.
        let slow: Vec<f64> = (0..15)
            .map(|i| if i / 3 == 2 { 1.0 } else { 0.1 })
            .collect();
        let means: Vec<Vec<f64>> = (0..40)
            .map(|_| {
                let a = 10.0 * r();
                slow.iter()
                    .zip(model.mean())
                    .map(|(s, m)| m + a * s + 0.01 * r())
                    .collect()
            })
            .collect();
        // Reference: the residuals' covariance and its largest eigenpair.
        let res: Vec<DVector<f64>> = means.iter().map(|x| residual_of(&model, x)).collect();
        let mean = res.iter().fold(DVector::zeros(15), |a, b| a + b) / res.len() as f64;
        let mut cov = DMatrix::zeros(15, 15);
        for x in &res {
            let d = x - &mean;
            cov += &d * d.transpose();
        }
        cov /= res.len() as f64;
        let eig = cov.symmetric_eigen();
        let top = eig.eigenvalues.imax();
        let v = eig.eigenvectors.column(top);
        let (marker, peak) = (0..5)
            .map(|k| (k, (0..3).map(|a| v[3 * k + a].powi(2)).sum::<f64>().sqrt()))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .expect("markers");
        let want = eig.eigenvalues[top].sqrt() * peak;
        let (got, at) = slow_residual_of_means(&model, &means).expect("enough blocks");
        assert_eq!(at, marker);
        assert!(want > 0.1, "the slow residual is not trivial: {want}");
        assert!((got - want).abs() <= 1e-6 * want, "{got} vs {want}");
        assert!(slow_residual_of_means(&model, &means[..7]).is_none());
    }
}
