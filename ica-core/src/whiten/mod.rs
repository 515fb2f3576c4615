//! Centring and PCA whitening (section 3.2 of the paper: `x = E{x} + P A u`).
//!
//! The covariance of the complete frames is accumulated in f64 (blocked gemm, upper triangle
//! only), decomposed by faer's symmetric eigensolver, and the principal axes are sorted by
//! variance. The first `m` axes, each scaled to unit variance, whiten the data; FastICA then
//! only has to find a rotation of them.
//!
//! Two ways in, one PCA ([`Whitener`]):
//! - in memory, [`whiten`] scans a [`FitData`] holding every frame;
//! - streaming, [`Moments`] accumulates mean and covariance chunk by chunk (mergeable, so
//!   chunks can be folded on several threads), [`Whitener::from_moments`] fits the same PCA,
//!   and [`Whitener::whiten_into`] whitens one chunk at a time into a caller buffer.

mod eigen;
mod kernels;
mod moments;
mod pca;
mod stats;
mod syrk;
mod transform;

pub use moments::Moments;
pub use pca::{noise_edge, Whitener};
pub use transform::FromF64;

use pca::Stats;

use nalgebra::DMatrix;

use crate::input::{FitData, FitError};

/// Smallest accepted variance target.
pub const MIN_VARIANCE_TARGET: f64 = 0.90;
/// Largest accepted variance target.
pub const MAX_VARIANCE_TARGET: f64 = 0.999;
/// Default variance target.
pub const DEFAULT_VARIANCE_TARGET: f64 = 0.97;
/// A channel whose variance is at most this share of the largest channel variance is dead
/// (constant marker, or a channel missing in every frame): it gets no loading and no weight.
pub const DEAD_CHANNEL_RELATIVE_VARIANCE: f64 = 1e-9;
/// Eigenvalues at most this share of the largest one count as numerically zero for the rank.
pub const RANK_RELATIVE_EIGENVALUE: f64 = 1e-10;

/// How many principal components (and so independent components) to keep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Components {
    /// The smallest `m` whose principal components explain at least this share of the variance,
    /// in [`MIN_VARIANCE_TARGET`, `MAX_VARIANCE_TARGET`].
    VarianceTarget(f64),
    /// Exactly `m` components; at least 1 and at most the data's rank.
    Fixed(usize),
    /// The variance target, but never past the noise floor: only components whose variance
    /// exceeds the largest eigenvalue white noise of variance `noise_var` per channel would
    /// reach with this many frames and channels (the Marchenko-Pastur edge
    /// `σ²(1 + √(channels/frames))²`). On a short or noisy session a fixed share of the
    /// variance reaches deep into noise; this keeps the components the data can tell from it.
    VarianceAboveNoise {
        /// The variance share, as [`Components::VarianceTarget`].
        target: f64,
        /// Noise variance per channel (mm²), measured on the capture.
        noise_var: f64,
    },
}

impl Default for Components {
    fn default() -> Self {
        Components::VarianceTarget(DEFAULT_VARIANCE_TARGET)
    }
}

impl Components {
    /// Checks the parameter alone (the rank check needs the data).
    ///
    /// # Errors
    /// [`FitError::VarianceTarget`] or [`FitError::ZeroComponents`].
    pub fn check(self) -> Result<(), FitError> {
        match self {
            Components::VarianceTarget(t)
                if !(MIN_VARIANCE_TARGET..=MAX_VARIANCE_TARGET).contains(&t) =>
            {
                Err(FitError::VarianceTarget {
                    target: t,
                    min: MIN_VARIANCE_TARGET,
                    max: MAX_VARIANCE_TARGET,
                })
            }
            Components::VarianceAboveNoise { target, .. } => {
                Components::VarianceTarget(target).check()
            }
            Components::Fixed(0) => Err(FitError::ZeroComponents),
            _ => Ok(()),
        }
    }
}

/// Centred, whitened training data and the PCA that produced it.
#[derive(Debug, Clone)]
pub struct Whitening {
    /// Per-channel mean over the used frames (channels long; 0 for channels missing everywhere).
    pub mean: Vec<f64>,
    /// Channels with about zero variance, ascending.
    pub dead_channels: Vec<usize>,
    /// The other channels, ascending: rows of `basis`.
    pub live_channels: Vec<usize>,
    /// Eigenvalues of the live covariance, largest first, negatives clamped to 0.
    pub eigenvalues: Vec<f64>,
    /// Numerical rank of the covariance.
    pub rank: usize,
    /// Share of the total variance explained by the kept components.
    pub variance_kept: f64,
    /// The kept principal axes, `live x m`, orthonormal columns, largest variance first.
    pub basis: DMatrix<f64>,
    /// Whitened used frames, `m x used` (one frame per column, unit covariance).
    pub whitened: DMatrix<f64>,
    /// Indices of the frames used (no missing sample), ascending.
    pub used_frames: Vec<usize>,
    /// Frames offered.
    pub frames_total: usize,
}

impl Whitening {
    /// Components kept (`m`).
    pub fn components(&self) -> usize {
        self.basis.ncols()
    }
}

/// Centres and whitens `data`, keeping `components` principal components.
///
/// # Errors
/// Non-finite present samples, fewer than `m + 1` (at least 2) complete frames, all channels
/// dead, a bad variance target, `m == 0` or `m` above the rank: see [`FitError`].
pub fn whiten<T: Copy + Into<f64>>(
    data: &FitData<'_, T>,
    components: Components,
) -> Result<Whitening, FitError> {
    let (w, whitened, used_frames) = whiten_parts(data, components)?;
    Ok(Whitening {
        mean: w.mean,
        dead_channels: w.dead_channels,
        live_channels: w.live_channels,
        eigenvalues: w.eigenvalues,
        rank: w.rank,
        variance_kept: w.variance_kept,
        basis: w.basis,
        whitened,
        used_frames,
        frames_total: w.frames_total,
    })
}

/// The fitted whitening, the whitened used frames (`m x used`) and the used frames' indices.
pub(crate) fn whiten_parts<T: Copy + Into<f64>>(
    data: &FitData<'_, T>,
    components: Components,
) -> Result<(Whitener, DMatrix<f64>, Vec<usize>), FitError> {
    components.check()?;
    let sel = stats::select(data)?;
    pca::check_frames(components, sel.used_frames.len(), data.frames())?;
    let mean = stats::mean(data, &sel);
    // The covariance of every channel seen at least once: its diagonal holds the variances that
    // classify dead channels, which saves a pass over the data.
    let seen: Vec<usize> = (0..data.channels())
        .filter(|&c| !sel.always_missing[c])
        .collect();
    if seen.is_empty() {
        return Err(FitError::NoVariance {
            channels: data.channels(),
        });
    }
    let cov = stats::covariance(data, &sel.used_frames, &seen, &mean);
    let w = Whitener::from_stats(
        Stats {
            mean,
            missing_everywhere: sel.always_missing,
            seen,
            cov,
            frames_used: sel.used_frames.len(),
            frames_total: data.frames(),
        },
        components,
    )?;
    let whitened = stats::project(data, &sel.used_frames, &w.live_channels, &w.mean, &w.rows);
    Ok((w, whitened, sel.used_frames))
}
