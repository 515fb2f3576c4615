//! Centring and PCA whitening (section 3.2 of the paper: `x = E{x} + P A u`).
//!
//! The covariance of the complete frames is accumulated in f64 (blocked gemm, upper triangle
//! only), decomposed with nalgebra's `SymmetricEigen`, and the principal axes are sorted by
//! variance. The first `m` axes, each scaled to unit variance, whiten the data; FastICA then
//! only has to find a rotation of them.

mod eigen;
mod stats;

use nalgebra::DMatrix;

use crate::fit::{FitData, FitError};

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
    components.check()?;
    let sel = stats::select(data)?;
    let needed = match components {
        Components::Fixed(m) => m + 1,
        Components::VarianceTarget(_) | Components::VarianceAboveNoise { .. } => 2,
    }
    .max(2);
    let used = sel.used_frames.len();
    if used < needed {
        return Err(FitError::TooFewFrames {
            used,
            total: data.frames(),
            needed,
        });
    }
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
    let (live, dead, cov) = classify_channels(data.channels(), &seen, cov)?;
    let mut eigenvalues = eigen::sorted_eigenvalues(&cov);
    let lmax = eigenvalues.first().copied().unwrap_or(0.0);
    let rank = eigenvalues
        .iter()
        .take_while(|&&l| l > RANK_RELATIVE_EIGENVALUE * lmax)
        .count();
    let m = choose_m(components, &eigenvalues, rank, used)?;
    let total: f64 = eigenvalues.iter().sum();
    let variance_kept = eigenvalues[..m].iter().sum::<f64>() / total;
    let (leading, basis) = eigen::leading(&cov, &eigenvalues, m);
    // The Rayleigh quotients of the kept axes scale them to exactly unit variance.
    eigenvalues[..m].copy_from_slice(&leading);
    let mut rows = basis.transpose();
    for (i, mut row) in rows.row_iter_mut().enumerate() {
        row /= eigenvalues[i].sqrt();
    }
    let whitened = stats::project(data, &sel.used_frames, &live, &mean, &rows);
    Ok(Whitening {
        mean,
        dead_channels: dead,
        live_channels: live,
        eigenvalues,
        rank,
        variance_kept,
        basis,
        whitened,
        used_frames: sel.used_frames,
        frames_total: data.frames(),
    })
}

/// Live channels, dead channels and the live block of the covariance.
type LiveSplit = (Vec<usize>, Vec<usize>, DMatrix<f64>);

/// Splits channels into live ones and dead ones (missing everywhere, or variance at most
/// [`DEAD_CHANNEL_RELATIVE_VARIANCE`] of the largest), given the covariance of the `seen`
/// channels; returns the live channels, the dead ones and the live block of the covariance.
/// A constant channel keeps its constant as mean, so the reconstruction `mean + M u` is right for
/// it; one never seen has mean 0.
fn classify_channels(
    channels: usize,
    seen: &[usize],
    cov: DMatrix<f64>,
) -> Result<LiveSplit, FitError> {
    let max_var = cov.diagonal().iter().copied().fold(0.0f64, f64::max);
    if max_var <= 0.0 {
        return Err(FitError::NoVariance { channels });
    }
    let keep: Vec<usize> = (0..seen.len())
        .filter(|&i| cov[(i, i)] > DEAD_CHANNEL_RELATIVE_VARIANCE * max_var)
        .collect();
    let mut is_live = vec![false; channels];
    keep.iter().for_each(|&i| is_live[seen[i]] = true);
    let (live, dead) = (0..channels).partition(|&c| is_live[c]);
    let cov = if keep.len() == seen.len() {
        cov
    } else {
        cov.select_rows(&keep).select_columns(&keep)
    };
    Ok((live, dead, cov))
}

/// The largest eigenvalue of the sample covariance of white noise with variance `noise_var`
/// per channel (Marchenko-Pastur edge).
pub fn noise_edge(noise_var: f64, channels: usize, frames: usize) -> f64 {
    let ratio = channels as f64 / frames.max(1) as f64;
    noise_var * (1.0 + ratio.sqrt()).powi(2)
}

/// Picks `m` from the request and the spectrum.
fn choose_m(
    components: Components,
    eigenvalues: &[f64],
    rank: usize,
    frames: usize,
) -> Result<usize, FitError> {
    match components {
        Components::VarianceAboveNoise { target, noise_var } => {
            let by_share = choose_m(
                Components::VarianceTarget(target),
                eigenvalues,
                rank,
                frames,
            )?;
            let edge = noise_edge(noise_var, eigenvalues.len(), frames);
            let signal = eigenvalues.iter().take(rank).filter(|&&l| l > edge).count();
            Ok(by_share.min(signal).max(1))
        }
        Components::Fixed(m) if m > rank => Err(FitError::ComponentsExceedRank { m, rank }),
        Components::Fixed(m) => Ok(m),
        Components::VarianceTarget(target) => {
            let total: f64 = eigenvalues.iter().sum();
            let mut acc = 0.0;
            for (i, &l) in eigenvalues.iter().enumerate().take(rank) {
                acc += l;
                if acc >= target * total {
                    return Ok(i + 1);
                }
            }
            Ok(rank.max(1))
        }
    }
}
