//! Filling gaps in training data so that frames with an occluded marker still teach the model.
//!
//! Whitening needs complete frames. A real capture has gaps (Facial-Sing: two cheek markers
//! missing for 4 s), and leaving out every frame with a gap leaves out whatever the face did
//! meanwhile: on Facial-Sing the model then reconstructs the visible markers of those frames
//! 3.7 mm off, against 0.7 mm elsewhere. Instead the gaps are filled by EM for probabilistic
//! PCA (Roweis 1998; Tipping & Bishop 1999):
//!
//! 1. PCA of the complete frames (the same component rule as training).
//! 2. Each gap is filled with the posterior mean given the frame's visible channels:
//!    `v = (A_oᵀ A_o + σ² I)⁻¹ A_oᵀ (x_o − mean_o)`, `x_h = mean_h + A_h v`, with
//!    `A = E Λ^½` the kept axes and `σ²` the variance per channel they leave out.
//! 3. PCA again, of every frame with the gaps filled; fill again from the visible values;
//!    [`EM_ITERATIONS`] times in all.
//!
//! Frames missing more than [`MAX_MISSING_SHARE`] of their channels are not filled and stay
//! out of training.

use nalgebra::{DMatrix, DVector};

use crate::input::{FitData, FitError};
use crate::whiten::{self, Components};

/// Rounds of PCA and filling.
pub const EM_ITERATIONS: usize = 3;
/// Frames missing more than this share of their channels are left out, not filled.
pub const MAX_MISSING_SHARE: f64 = 0.5;

/// What [`fill_gaps`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GapFill {
    /// Frames with gaps that were filled.
    pub frames: usize,
    /// Samples (channels) filled.
    pub samples: usize,
    /// Frames left missing (too many gaps).
    pub frames_left_out: usize,
}

/// Fills the gaps of `samples` (frames x channels) in place; returns the mask of what is still
/// missing afterwards (only frames with too many gaps) and what was done. See the module docs.
///
/// # Errors
/// Whatever whitening the complete frames fails with (too few complete frames, no variance,
/// a bad component rule).
pub fn fill_gaps(
    samples: &mut [f32],
    missing: &[bool],
    channels: usize,
    components: Components,
) -> Result<(Vec<bool>, GapFill), FitError> {
    let frames = missing.len() / channels.max(1);
    let gappy = |f: usize| missing[f * channels..(f + 1) * channels].iter().any(|&m| m);
    let too_many = |f: usize| {
        let gone = missing[f * channels..(f + 1) * channels]
            .iter()
            .filter(|&&m| m)
            .count();
        gone as f64 > MAX_MISSING_SHARE * channels as f64
    };
    let fillable: Vec<usize> = (0..frames).filter(|&f| gappy(f) && !too_many(f)).collect();
    let mut after: Vec<bool> = missing.to_vec();
    let mut report = GapFill {
        frames_left_out: (0..frames).filter(|&f| too_many(f)).count(),
        ..GapFill::default()
    };
    if fillable.is_empty() {
        return Ok((after, report));
    }
    // Channels missing in every frame stay missing (whitening marks them dead).
    let mut seen = vec![false; channels];
    for (i, &m) in missing.iter().enumerate() {
        seen[i % channels] |= !m;
    }
    for iteration in 0..EM_ITERATIONS {
        // The first round learns from complete frames only; later rounds from the filled ones.
        let mask: &[bool] = if iteration == 0 { missing } else { &after };
        let data = FitData::new(&*samples, channels)?.with_missing(mask)?;
        let pca = whiten::whiten(&data, components)?;
        let model = Ppca::new(&pca, channels);
        for &f in &fillable {
            let frame = &mut samples[f * channels..(f + 1) * channels];
            model.fill(frame, &missing[f * channels..(f + 1) * channels]);
        }
        if iteration == 0 {
            for &f in &fillable {
                for c in 0..channels {
                    after[f * channels + c] = missing[f * channels + c] && !seen[c];
                }
            }
        }
    }
    report.frames = fillable.len();
    report.samples = fillable
        .iter()
        .map(|&f| {
            (0..channels)
                .filter(|&c| missing[f * channels + c] && seen[c])
                .count()
        })
        .sum();
    Ok((after, report))
}

/// A PCA read as a probabilistic PCA, over all channels (dead ones have zero loadings).
struct Ppca {
    mean: Vec<f64>,
    /// `A = E Λ^½`, channels x m.
    loadings: DMatrix<f64>,
    /// Variance per live channel the kept axes leave out.
    residual: f64,
}

impl Ppca {
    fn new(w: &whiten::Whitening, channels: usize) -> Ppca {
        let m = w.components();
        let mut loadings = DMatrix::zeros(channels, m);
        for (r, &c) in w.live_channels.iter().enumerate() {
            for k in 0..m {
                loadings[(c, k)] = w.basis[(r, k)] * w.eigenvalues[k].sqrt();
            }
        }
        let left: f64 = w.eigenvalues.iter().skip(m).sum();
        Ppca {
            mean: w.mean.clone(),
            loadings,
            residual: left / w.live_channels.len().max(1) as f64,
        }
    }

    /// Fills the `missing` channels of `frame` with their posterior mean.
    fn fill(&self, frame: &mut [f32], missing: &[bool]) {
        let m = self.loadings.ncols();
        let mut gram = DMatrix::<f64>::identity(m, m) * self.residual.max(1e-12);
        let mut rhs = DVector::<f64>::zeros(m);
        for (c, &gone) in missing.iter().enumerate() {
            if gone {
                continue;
            }
            let row = self.loadings.row(c);
            let centred = f64::from(frame[c]) - self.mean[c];
            gram += row.transpose() * row;
            rhs += row.transpose() * centred;
        }
        let Some(chol) = gram.cholesky() else {
            return;
        };
        let v = chol.solve(&rhs);
        for (c, &gone) in missing.iter().enumerate() {
            if gone {
                frame[c] = (self.mean[c] + self.loadings.row(c).dot(&v.transpose())) as f32;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::mixture;

    #[test]
    fn gaps_are_filled_close_to_the_hidden_values() {
        let mix = mixture::face_like(3000, 30, 4, 0.05, 3);
        let channels = mix.channels;
        let truth = mix.samples.clone();
        let mut samples = truth.clone();
        let mut missing = vec![false; truth.len()];
        // A marker (3 channels) gone for a block of 400 frames, and one frame mostly gone.
        for f in 1000..1400 {
            for c in 6..9 {
                missing[f * channels + c] = true;
                samples[f * channels + c] = f32::NAN;
            }
        }
        for c in 0..20 {
            missing[2000 * channels + c] = true;
        }
        let (after, report) =
            fill_gaps(&mut samples, &missing, channels, Components::Fixed(4)).expect("fills");
        assert_eq!(report.frames, 400);
        assert_eq!(report.samples, 1200);
        assert_eq!(report.frames_left_out, 1);
        assert!(after[2000 * channels]);
        assert!(!after[1000 * channels + 6]);
        let spread = (0..3000)
            .map(|f| f64::from(truth[f * channels + 7]).powi(2))
            .sum::<f64>()
            / 3000.0;
        let err = (1000..1400)
            .map(|f| f64::from(samples[f * channels + 7] - truth[f * channels + 7]).powi(2))
            .sum::<f64>()
            / 400.0;
        assert!(err < 0.01 * spread, "error {err} vs spread {spread}");
    }
}
