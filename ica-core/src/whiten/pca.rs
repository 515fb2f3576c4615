//! The fitted PCA whitening transform, built from a covariance: shared by the in-memory
//! [`super::whiten`] and the streaming path ([`Whitener::from_moments`]), so both pick the same
//! dead channels, components and axes from the same statistics.

use nalgebra::DMatrix;

use super::stats::frame_is_used;
use super::{eigen, Components, Moments, DEAD_CHANNEL_RELATIVE_VARIANCE, RANK_RELATIVE_EIGENVALUE};
use crate::input::FitError;

/// PCA whitening fitted to the used frames, without the data: `z = Λ^{-1/2} Eᵀ (x - mean)` on
/// the live channels.
///
/// Built by [`Whitener::from_moments`] (streaming) or inside [`super::whiten`] (in memory);
/// [`Whitener::whiten_into`] applies it to a chunk of frames.
#[derive(Debug, Clone)]
pub struct Whitener {
    /// Per-channel mean over the used frames (channels long; 0 for channels missing everywhere).
    pub mean: Vec<f64>,
    /// Channels with about zero variance or missing in every frame, ascending.
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
    /// Frames the statistics were taken over (no missing sample).
    pub frames_used: usize,
    /// Frames offered.
    pub frames_total: usize,
    /// `Λ^{-1/2} Eᵀ`, `m x live`.
    pub(crate) rows: DMatrix<f64>,
    /// Channels missing in every frame (a frame is used when exactly these are missing).
    pub(crate) missing_everywhere: Vec<bool>,
}

/// What the PCA is computed from: the statistics of the used frames.
pub(crate) struct Stats {
    /// Per-channel mean (channels long).
    pub mean: Vec<f64>,
    /// Channels missing in every frame.
    pub missing_everywhere: Vec<bool>,
    /// Channels not missing everywhere, ascending.
    pub seen: Vec<usize>,
    /// Unbiased covariance of the `seen` channels.
    pub cov: DMatrix<f64>,
    /// Frames used.
    pub frames_used: usize,
    /// Frames offered.
    pub frames_total: usize,
}

impl Whitener {
    /// Fits the whitening to streamed statistics, exactly as [`super::whiten`] would to the
    /// same frames held in memory.
    ///
    /// # Errors
    /// A bad component request, fewer than `m + 1` (at least 2) used frames, every channel dead,
    /// or `m` above the rank: see [`FitError`].
    pub fn from_moments(moments: &Moments, components: Components) -> Result<Self, FitError> {
        components.check()?;
        check_frames(components, moments.frames_used(), moments.frames_total())?;
        let missing = moments.missing_everywhere().to_vec();
        let seen: Vec<usize> = (0..moments.channels()).filter(|&c| !missing[c]).collect();
        if seen.is_empty() {
            return Err(FitError::NoVariance {
                channels: moments.channels(),
            });
        }
        let cov = moments.covariance_of(&seen);
        Self::from_stats(
            Stats {
                mean: moments.mean().to_vec(),
                missing_everywhere: missing,
                seen,
                cov,
                frames_used: moments.frames_used(),
                frames_total: moments.frames_total(),
            },
            components,
        )
    }

    /// Components kept (`m`).
    pub fn components(&self) -> usize {
        self.basis.ncols()
    }

    /// Channels per frame.
    pub fn channels(&self) -> usize {
        self.mean.len()
    }

    /// The whitening matrix `Λ^{-1/2} Eᵀ`, `m x live` (columns in `live_channels` order).
    pub fn whitening_matrix(&self) -> &DMatrix<f64> {
        &self.rows
    }

    /// Whether a frame with these missing flags (`None`: nothing missing) is used: exactly the
    /// channels missing in every frame may be missing.
    pub fn frame_is_used(&self, missing: Option<&[bool]>) -> bool {
        frame_is_used(&self.missing_everywhere, missing)
    }

    /// The PCA of `stats`: dead channels, spectrum, `m`, the kept axes and the whitening rows.
    pub(crate) fn from_stats(stats: Stats, components: Components) -> Result<Self, FitError> {
        let channels = stats.mean.len();
        let (live, dead, cov) = classify_channels(channels, &stats.seen, stats.cov)?;
        let (eigenvalues, axes) = eigen::decompose(&cov)?;
        let lmax = eigenvalues.first().copied().unwrap_or(0.0);
        let rank = eigenvalues
            .iter()
            .take_while(|&&l| l > RANK_RELATIVE_EIGENVALUE * lmax)
            .count();
        let m = choose_m(components, &eigenvalues, rank, stats.frames_used)?;
        let total: f64 = eigenvalues.iter().sum();
        let variance_kept = eigenvalues[..m].iter().sum::<f64>() / total;
        let mut basis = axes.columns(0, m).into_owned();
        sign_axes(&mut basis);
        let mut rows = basis.transpose();
        for (i, mut row) in rows.row_iter_mut().enumerate() {
            row /= eigenvalues[i].sqrt();
        }
        Ok(Whitener {
            mean: stats.mean,
            dead_channels: dead,
            live_channels: live,
            eigenvalues,
            rank,
            variance_kept,
            basis,
            frames_used: stats.frames_used,
            frames_total: stats.frames_total,
            rows,
            missing_everywhere: stats.missing_everywhere,
        })
    }
}

/// Signs each axis so that its largest-magnitude loading is positive.
///
/// Eigen-solvers return an axis with either sign, and which one is decided by rounding noise:
/// one ulp in one sample of a take flipped axes of the whole fit. The sign does not change the
/// whitened space, but the seeded restarts start from fixed matrices in it, so it decided where
/// they started and so the result at the level of the convergence tolerance. With the axes
/// signed by the data, the in-memory and the streaming fit (whose covariances differ by
/// rounding) start from the same points and end at the same rotation.
fn sign_axes(basis: &mut DMatrix<f64>) {
    for mut axis in basis.column_iter_mut() {
        if axis[axis.iamax()] < 0.0 {
            axis.neg_mut();
        }
    }
}

/// Fewer than `m + 1` (at least 2) used frames cannot give a rank-`m` covariance.
pub(crate) fn check_frames(
    components: Components,
    used: usize,
    total: usize,
) -> Result<(), FitError> {
    let needed = match components {
        Components::Fixed(m) => m + 1,
        Components::VarianceTarget(_) | Components::VarianceAboveNoise { .. } => 2,
    }
    .max(2);
    if used < needed {
        return Err(FitError::TooFewFrames {
            used,
            total,
            needed,
        });
    }
    Ok(())
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

/// Picks `m` from the request, the spectrum and the number of frames behind it.
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

#[cfg(test)]
mod tests;
