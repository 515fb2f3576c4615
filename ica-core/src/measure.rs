//! The numbers behind a model's quality report ([`crate::quality`]), measured on its
//! training frames.

use std::ops::Range;

use nalgebra::{DMatrix, DVector};

use crate::model::IcaModel;
use crate::robust::{mad, median};

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

/// Working vectors of [`residual_into`].
struct Residual {
    centred: DVector<f64>,
    u: DVector<f64>,
    r: DVector<f64>,
}

impl Residual {
    fn new(model: &IcaModel) -> Self {
        let c = model.channels();
        Self {
            centred: DVector::zeros(c),
            u: DVector::zeros(model.components()),
            r: DVector::zeros(c),
        }
    }

    /// The residual `(x − mean) − M W (x − mean)` of `x` (a complete frame, or a mean of
    /// complete frames: the residual is linear in `x`), into `self.r`.
    fn of(&mut self, model: &IcaModel, x: impl Iterator<Item = f64>) -> &DVector<f64> {
        for ((v, x), mu) in self.centred.iter_mut().zip(x).zip(model.mean()) {
            *v = x - mu;
        }
        self.u.gemv(1.0, model.unmixing(), &self.centred, 0.0);
        self.r.copy_from(&self.centred);
        self.r.gemv(-1.0, model.mixing(), &self.u, 1.0);
        &self.r
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
    let mut res = Residual::new(model);
    let mut sq = vec![0.0; model.markers()];
    let mut count = 0usize;
    for x in frames {
        let r = res.of(model, x.iter().map(|&v| f64::from(v)));
        for (k, s) in sq.iter_mut().enumerate() {
            *s += r[3 * k].powi(2) + r[3 * k + 1].powi(2) + r[3 * k + 2].powi(2);
        }
        count += 1;
    }
    sq.iter()
        .map(|s| (s / count.max(1) as f64).sqrt())
        .collect()
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
    let mut res = Residual::new(model);
    let mut blocks: Vec<DVector<f64>> = Vec::new();
    let stride_blocks = slow_block_stride(data.frames(), block);
    for take in data.takes {
        let mut acc = DVector::zeros(c);
        let mut filled = 0usize;
        let mut index = 0usize;
        for f in take.clone() {
            if !data.complete(f) {
                acc.fill(0.0);
                filled = 0;
                continue;
            }
            acc += res.of(model, data.frame(f).iter().map(|&v| f64::from(v)));
            filled += 1;
            if filled == block {
                if index % stride_blocks == 0 {
                    blocks.push(&acc / block as f64);
                }
                index += 1;
                acc.fill(0.0);
                filled = 0;
            }
        }
    }
    slow_direction(blocks, c)
}

/// [`slow_residual`] from the kept blocks' mean frames (the residual is linear, so the
/// residual of a block's mean is the block's mean residual), as a streaming caller collects
/// them.
pub fn slow_residual_of_means(model: &IcaModel, means: &[Vec<f64>]) -> Option<(f64, usize)> {
    let mut res = Residual::new(model);
    let blocks = means
        .iter()
        .map(|x| res.of(model, x.iter().copied()).clone())
        .collect();
    slow_direction(blocks, model.channels())
}

/// The leading direction of the block residuals at its peak marker.
fn slow_direction(blocks: Vec<DVector<f64>>, c: usize) -> Option<(f64, usize)> {
    if blocks.len() < 8 {
        return None;
    }
    let mean = blocks.iter().fold(DVector::zeros(c), |a, b| a + b) / blocks.len() as f64;
    let b = DMatrix::from_fn(blocks.len(), c, |i, j| blocks[i][j] - mean[j]);
    let (lambda, v) = leading_direction(&b);
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

/// Largest eigenvalue of `bᵀb / rows` and its unit eigenvector, by power iteration.
fn leading_direction(b: &DMatrix<f64>) -> (f64, DVector<f64>) {
    let c = b.ncols();
    let mut v = DVector::from_fn(c, |i, _| 1.0 + (i % 7) as f64 * 0.1);
    v.normalize_mut();
    let mut lambda = 0.0;
    let mut t = DVector::zeros(b.nrows());
    let mut w = DVector::zeros(c);
    for _ in 0..200 {
        t.gemv(1.0, b, &v, 0.0);
        w.gemv_tr(1.0 / b.nrows() as f64, b, &t, 0.0);
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
    let mut spread: Vec<f64> = per_channel
        .iter_mut()
        .filter(|d2| d2.len() >= 10)
        .map(|d2| mad(d2) / 6f64.sqrt())
        .collect();
    median(&mut spread)
}
