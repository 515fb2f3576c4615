//! Training: whitening + FastICA restarts + the sign/order convention, in one call.
//!
//! ```
//! use ica_core::fit::{mixture, FastIcaParams, FitData};
//! let mix = mixture::face_like(2000, 30, 4, 0.2, 1);
//! let data = FitData::new(&mix.samples, mix.channels).expect("whole frames");
//! let out = FastIcaParams::default().n_components(4).fit(&data).expect("fit");
//! assert_eq!(out.mixing.shape(), (30, 4));
//! assert!(out.report.restarts[out.report.best_restart].solution_converged());
//! ```
//!
//! On long takes (at least twice [`crate::fastica::EXPLORE_FRAMES`] used frames, more than one
//! restart) the restarts run on an evenly strided subsample and only the winner is refined on all
//! frames; the winner's [`crate::RestartReport::refinement`] says how that went.
//!
//! The model is `x ≈ mean + M u` with `M = P A` (paper eq. 2) in the original channel space and
//! `u = W (x - mean)` with `W` the whitening followed by the ICA rotation.
//!
//! # Sign and order convention
//! ICA leaves each component's sign and the components' order free. Here components are ordered
//! by the marker-space variance they explain, `|M_i|^2` (the squared norm of mixing column `i`, as
//! every `u_i` has unit variance), largest first. Each is signed so that its skewness over the
//! training frames is positive; when the skewness is not distinguishable from zero (below
//! [`SKEW_SIGNIFICANT`] standard errors, `sqrt(6/T)`), the largest-magnitude loading of its mixing
//! column is made positive instead.

mod amari;
mod data;
mod error;
pub mod mixture;
mod params;

pub use amari::amari_index;
pub use data::FitData;
pub use error::FitError;
pub use params::{FastIcaParams, DEFAULT_MAX_ITER, DEFAULT_RESTARTS, DEFAULT_SEED, DEFAULT_TOL};

pub use crate::fastica::{Algorithm, Contrast};
pub use crate::whiten::Components;

use nalgebra::DMatrix;

use crate::fastica::{self, Settings};
use crate::whiten::{self, Whitening};
use crate::TrainReport;

/// Skewness below this many standard errors counts as zero for the sign convention.
pub const SKEW_SIGNIFICANT: f64 = 3.0;

/// A trained decomposition: `x ≈ mean + mixing · u`, `u = unmixing · (x - mean)`.
#[derive(Debug, Clone)]
pub struct FitOutput {
    /// Per-channel mean of the used frames (`channels` long).
    pub mean: Vec<f64>,
    /// `M = P A`, `channels x m`: column `i` is component `i`'s displacement per unit of `u_i`.
    /// Rows of dead channels are zero.
    pub mixing: DMatrix<f64>,
    /// `W`, `m x channels`: whitening then rotation. Columns of dead channels are zero, so a dead
    /// channel's value never reaches `u`. `unmixing · mixing = I`.
    pub unmixing: DMatrix<f64>,
    /// Marker-space variance each component explains, `|M_i|^2`, in component order (decreasing).
    pub component_variance: Vec<f64>,
    /// The components of the used frames, `frames_used x m` (row `r` is frame `used_frames[r]`),
    /// unit variance; `None` if [`FastIcaParams::keep_sources`] was off.
    pub sources: Option<DMatrix<f64>>,
    /// Indices of the frames used for training, ascending.
    pub used_frames: Vec<usize>,
    /// What training did.
    pub report: TrainReport,
}

impl FastIcaParams {
    /// Fits the decomposition to `data`.
    ///
    /// Deterministic: the same data and parameters give bit-identical output.
    ///
    /// # Errors
    /// A bad parameter, non-finite present samples, too few complete frames, all channels dead,
    /// or `m` above the data's rank: see [`FitError`].
    pub fn fit<T: Copy + Into<f64>>(&self, data: &FitData<'_, T>) -> Result<FitOutput, FitError> {
        self.check()?;
        let wh = whiten::whiten(data, self.components)?;
        let run = fastica::run(
            &wh.whitened,
            Settings {
                contrast: self.contrast,
                algorithm: self.algorithm,
                tol: self.tol,
                max_iter: self.max_iter,
                seed: self.seed,
                restarts: self.restarts,
            },
        );
        let stability = fastica::stability(&run.w, &run.restart_w, run.best);
        let (mixing, unmixing, sources) = assemble(&wh, &run.w, run.sources, data.channels());
        let (mixing, unmixing, sources, component_variance, order) =
            canonicalise(mixing, unmixing, sources);
        let stability = if stability.is_empty() {
            stability
        } else {
            order.iter().map(|&i| stability[i]).collect()
        };
        let report = TrainReport {
            frames_total: wh.frames_total,
            frames_used: wh.used_frames.len(),
            channels: data.channels(),
            dead_channels: wh.dead_channels.clone(),
            components: wh.components(),
            variance_kept: wh.variance_kept,
            eigenvalues: wh.eigenvalues.clone(),
            contrast: self.contrast.name().to_owned(),
            algorithm: self.algorithm.name().to_owned(),
            tol: self.tol,
            max_iter: self.max_iter,
            restarts: run.restarts,
            best_restart: run.best,
            stability,
        };
        Ok(FitOutput {
            mean: wh.mean,
            mixing,
            unmixing,
            component_variance,
            sources: self.keep_sources.then_some(sources),
            used_frames: wh.used_frames,
            report,
        })
    }
}

/// Maps the rotation back to channel space: `M = E sqrt(Λ) Wᵀ`, `W_full = W Λ^{-1/2} Eᵀ`, with
/// zero rows/columns for dead channels.
fn assemble(
    wh: &Whitening,
    w: &DMatrix<f64>,
    sources: DMatrix<f64>,
    channels: usize,
) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let m = wh.components();
    let mut scaled = wh.basis.clone();
    let mut inv_scaled = wh.basis.clone();
    for k in 0..m {
        let s = wh.eigenvalues[k].sqrt();
        scaled.column_mut(k).scale_mut(s);
        inv_scaled.column_mut(k).unscale_mut(s);
    }
    let mixing_live = scaled * w.transpose();
    let unmixing_live = w * inv_scaled.transpose();
    let mut mixing = DMatrix::zeros(channels, m);
    let mut unmixing = DMatrix::zeros(m, channels);
    for (r, &c) in wh.live_channels.iter().enumerate() {
        mixing.row_mut(c).copy_from(&mixing_live.row(r));
        unmixing.column_mut(c).copy_from(&unmixing_live.column(r));
    }
    (mixing, unmixing, sources)
}

/// Mixing, unmixing and sources in canonical order and sign, each component's variance, and
/// the original index of each canonical component.
type Canonical = (
    DMatrix<f64>,
    DMatrix<f64>,
    DMatrix<f64>,
    Vec<f64>,
    Vec<usize>,
);

/// Applies the sign and order convention (see the module docs).
fn canonicalise(mixing: DMatrix<f64>, unmixing: DMatrix<f64>, sources: DMatrix<f64>) -> Canonical {
    let m = mixing.ncols();
    let variance: Vec<f64> = mixing.column_iter().map(|c| c.norm_squared()).collect();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| variance[b].total_cmp(&variance[a]));
    let frames = sources.nrows();
    let threshold = SKEW_SIGNIFICANT * (6.0 / frames.max(1) as f64).sqrt();
    let signs: Vec<f64> = (0..m)
        .map(|i| {
            let skew = skewness(&sources.as_slice()[i * frames..(i + 1) * frames]);
            if skew.abs() >= threshold {
                skew.signum()
            } else {
                let col = mixing.column(i);
                let k = col.iamax();
                if col[k] < 0.0 {
                    -1.0
                } else {
                    1.0
                }
            }
        })
        .collect();
    let mix = DMatrix::from_fn(mixing.nrows(), m, |r, c| {
        mixing[(r, order[c])] * signs[order[c]]
    });
    let unmix = DMatrix::from_fn(m, unmixing.ncols(), |r, c| {
        unmixing[(order[r], c)] * signs[order[r]]
    });
    let src = DMatrix::from_fn(frames, m, |r, c| sources[(r, order[c])] * signs[order[c]]);
    let variance = order.iter().map(|&i| variance[i]).collect();
    (mix, unmix, src, variance, order)
}

/// Sample skewness `E (y - ȳ)^3 / σ^3` (0 for a constant or empty series).
pub(crate) fn skewness(ys: &[f64]) -> f64 {
    if ys.is_empty() {
        return 0.0;
    }
    let n = ys.len() as f64;
    let mean = ys.iter().sum::<f64>() / n;
    let (m2, m3) = ys.iter().fold((0.0, 0.0), |(a, b), &y| {
        let d = y - mean;
        (a + d * d, b + d * d * d)
    });
    let (m2, m3) = (m2 / n, m3 / n);
    if m2 <= 0.0 {
        0.0
    } else {
        m3 / m2.powf(1.5)
    }
}
