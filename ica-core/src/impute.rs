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
//!
//! For sessions too long to hold, the same rounds run over a stream: [`frame_gaps`] sorts
//! each frame, [`GapModel::from_whitener`] reads the PCA of streamed moments
//! ([`crate::whiten::Moments`], [`crate::whiten::Moments::merge_filled`]) as the model that
//! fills, one pass over the gappy frames per round.

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

use crate::input::{FitData, FitError};
use crate::whiten::{self, Components, Whitener};

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

/// What a frame's gaps make of it in training.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameGaps {
    /// Nothing missing.
    Complete,
    /// Some channels missing: filled.
    Fill,
    /// More than [`MAX_MISSING_SHARE`] of the channels missing: left out.
    LeaveOut,
}

/// How [`fill_gaps`] treats a frame with these missing flags.
pub fn frame_gaps(missing: &[bool]) -> FrameGaps {
    let gone = missing.iter().filter(|&&m| m).count();
    if gone == 0 {
        FrameGaps::Complete
    } else if gone as f64 > MAX_MISSING_SHARE * missing.len() as f64 {
        FrameGaps::LeaveOut
    } else {
        FrameGaps::Fill
    }
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
    let gaps = |f: usize| frame_gaps(&missing[f * channels..(f + 1) * channels]);
    let fillable: Vec<usize> = (0..frames)
        .filter(|&f| gaps(f) == FrameGaps::Fill)
        .collect();
    let mut after: Vec<bool> = missing.to_vec();
    let mut report = GapFill {
        frames_left_out: (0..frames)
            .filter(|&f| gaps(f) == FrameGaps::LeaveOut)
            .count(),
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
        let model = GapModel::new(&pca, channels);
        let mut filler = model.filler();
        for &f in &fillable {
            let frame = &mut samples[f * channels..(f + 1) * channels];
            filler.fill(frame, &missing[f * channels..(f + 1) * channels]);
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

/// A PCA read as a probabilistic PCA, over all channels (dead ones have zero loadings): the
/// model one round of [`fill_gaps`] fills with.
#[derive(Debug, Clone)]
pub struct GapModel {
    mean: Vec<f64>,
    /// `A = E Λ^½`, channels x m, row by row: a frame's fill reads a channel's row at a time.
    loadings: Vec<f64>,
    /// Kept axes (m).
    axes: usize,
    /// `σ² I + Σ a_c a_cᵀ` over every channel, m x m: a frame's system is this less its
    /// missing channels' terms.
    gram: DMatrix<f64>,
}

impl GapModel {
    fn new(w: &whiten::Whitening, channels: usize) -> GapModel {
        Self::from_parts(
            &w.mean,
            &w.live_channels,
            &w.basis,
            &w.eigenvalues,
            channels,
        )
    }

    /// The model of a fitted whitening (a streamed PCA), as [`fill_gaps`] builds it from an
    /// in-memory one.
    pub fn from_whitener(w: &Whitener) -> GapModel {
        Self::from_parts(
            &w.mean,
            &w.live_channels,
            &w.basis,
            &w.eigenvalues,
            w.channels(),
        )
    }

    fn from_parts(
        mean: &[f64],
        live: &[usize],
        basis: &DMatrix<f64>,
        eigenvalues: &[f64],
        channels: usize,
    ) -> GapModel {
        let m = basis.ncols();
        let mut loadings = vec![0.0; channels * m];
        for (r, &c) in live.iter().enumerate() {
            for k in 0..m {
                loadings[c * m + k] = basis[(r, k)] * eigenvalues[k].sqrt();
            }
        }
        let left: f64 = eigenvalues.iter().skip(m).sum();
        let residual = left / live.len().max(1) as f64;
        let mut gram = DMatrix::<f64>::zeros(m, m);
        gram.fill_diagonal(residual.max(1e-12));
        for row in loadings.chunks_exact(m.max(1)) {
            add_outer(&mut gram, row, 1.0);
        }
        GapModel {
            mean: mean.to_vec(),
            loadings,
            axes: m,
            gram,
        }
    }

    /// Fills the `missing` channels of `frame` with their posterior mean given the others.
    /// To fill many frames, [`GapModel::filler`] reuses the work frames with the same gaps
    /// share.
    pub fn fill(&self, frame: &mut [f32], missing: &[bool]) {
        self.filler().fill(frame, missing);
    }

    /// A filler of frame after frame with this model.
    pub fn filler(&self) -> GapFiller<'_> {
        GapFiller {
            model: self,
            missing: Vec::new(),
            factor: None,
            rhs: DVector::zeros(self.axes),
        }
    }
}

/// Fills frames with a [`GapModel`], keeping the factor of the last frame's missing set: a gap
/// runs over many frames, and every frame of it has the same system to solve, so only its
/// right-hand side is new. The numbers are those of [`GapModel::fill`] frame by frame.
#[derive(Debug)]
pub struct GapFiller<'a> {
    model: &'a GapModel,
    /// The missing set `factor` belongs to (empty: none yet).
    missing: Vec<bool>,
    /// Cholesky factor of `σ² I + Σ a_c a_cᵀ` over the visible channels (`None` when it is
    /// not positive definite: such a frame is left as it is).
    factor: Option<Cholesky<f64, Dyn>>,
    rhs: DVector<f64>,
}

impl GapFiller<'_> {
    /// Fills the `missing` channels of `frame` with their posterior mean given the others.
    pub fn fill(&mut self, frame: &mut [f32], missing: &[bool]) {
        let model = self.model;
        let m = model.axes;
        if self.missing != missing {
            // `σ² I + Σ a_c a_cᵀ` over the visible channels: the model's sum over every
            // channel less the missing ones' terms (a few channels in a frame worth filling,
            // against the half or more that are visible).
            let mut gram = model.gram.clone();
            for (c, _) in missing.iter().enumerate().filter(|(_, &gone)| gone) {
                add_outer(&mut gram, &model.loadings[c * m..(c + 1) * m], -1.0);
            }
            self.factor = gram.cholesky();
            self.missing.clear();
            self.missing.extend_from_slice(missing);
        }
        let Some(factor) = &self.factor else {
            return;
        };
        // `Σ a_c (x_c − mean_c)` over the visible channels.
        self.rhs.fill(0.0);
        for (c, _) in missing.iter().enumerate().filter(|(_, &gone)| !gone) {
            let row = &model.loadings[c * m..(c + 1) * m];
            let centred = f64::from(frame[c]) - model.mean[c];
            (self.rhs.as_mut_slice().iter_mut())
                .zip(row)
                .for_each(|(r, &a)| *r += a * centred);
        }
        factor.solve_mut(&mut self.rhs);
        for (c, _) in missing.iter().enumerate().filter(|(_, &gone)| gone) {
            let row = &model.loadings[c * m..(c + 1) * m];
            let fitted = row
                .iter()
                .zip(self.rhs.iter())
                .fold(0.0, |s, (a, b)| s + a * b);
            frame[c] = (model.mean[c] + fitted) as f32;
        }
    }
}

/// `gram += sign · a aᵀ` (m x m, `a` of m values), column by column of its storage as plain
/// slices (nalgebra's element iterators cost several times the arithmetic here).
fn add_outer(gram: &mut DMatrix<f64>, a: &[f64], sign: f64) {
    let columns = gram.as_mut_slice().chunks_exact_mut(a.len().max(1));
    for (column, &aj) in columns.zip(a) {
        let scaled = sign * aj;
        column
            .iter_mut()
            .zip(a)
            .for_each(|(g, &ai)| *g += ai * scaled);
    }
}

#[cfg(test)]
mod tests;
