//! From a rotation of the whitened data to the fitted output: back to channel space, then the
//! sign and order convention. Shared by the in-memory and the streaming fit, which differ only
//! in where the components' skewness comes from (kept sources, or streamed third moments).

use nalgebra::DMatrix;

use super::{FastIcaParams, FitOutput, SKEW_SIGNIFICANT};
use crate::fastica;
use crate::whiten::Whitener;
use crate::{RestartReport, TrainReport};

/// What FastICA produced: the kept rotation and every restart.
#[derive(Debug)]
pub(crate) struct Solved {
    /// The kept rotation, `m x m`.
    pub w: DMatrix<f64>,
    /// Each restart's report, in run order.
    pub restarts: Vec<RestartReport>,
    /// Index of the kept restart.
    pub best: usize,
    /// Each restart's rotation (the best one before any refinement).
    pub restart_w: Vec<DMatrix<f64>>,
}

/// The canonical order (original index of each canonical component) and each original
/// component's sign.
#[derive(Debug)]
pub(crate) struct Canonical {
    order: Vec<usize>,
    signs: Vec<f64>,
}

impl Canonical {
    /// `sources` (`frames x m`) in canonical order and sign.
    pub(crate) fn sources(&self, sources: &DMatrix<f64>) -> DMatrix<f64> {
        let (order, signs) = (&self.order, &self.signs);
        DMatrix::from_fn(sources.nrows(), order.len(), |r, c| {
            sources[(r, order[c])] * signs[order[c]]
        })
    }
}

/// The fitted output of `solved` (no sources, no used-frame list: the caller adds what it has)
/// and the convention applied. `skewness[i]` is the skewness of component `i` of `solved.w`
/// over the `frames` used frames.
pub(crate) fn output(
    params: &FastIcaParams,
    wh: &Whitener,
    solved: Solved,
    skewness: &[f64],
    frames: usize,
) -> (FitOutput, Canonical) {
    let channels = wh.channels();
    let stability = fastica::stability(&solved.w, &solved.restart_w, solved.best);
    let (mixing, unmixing) = to_channels(wh, &solved.w);
    let canon = canonical(&mixing, skewness, frames);
    let (order, signs) = (&canon.order, &canon.signs);
    let m = order.len();
    let variance: Vec<f64> = mixing.column_iter().map(|c| c.norm_squared()).collect();
    let mix = DMatrix::from_fn(channels, m, |r, c| mixing[(r, order[c])] * signs[order[c]]);
    let unmix = DMatrix::from_fn(m, channels, |r, c| {
        unmixing[(order[r], c)] * signs[order[r]]
    });
    let stability = if stability.is_empty() {
        stability
    } else {
        order.iter().map(|&i| stability[i]).collect()
    };
    let report = TrainReport {
        frames_total: wh.frames_total,
        frames_used: wh.frames_used,
        channels,
        dead_channels: wh.dead_channels.clone(),
        components: wh.components(),
        variance_kept: wh.variance_kept,
        eigenvalues: wh.eigenvalues.clone(),
        contrast: params.contrast.name().to_owned(),
        algorithm: params.algorithm.name().to_owned(),
        tol: params.tol,
        max_iter: params.max_iter,
        restarts: solved.restarts,
        best_restart: solved.best,
        stability,
    };
    let out = FitOutput {
        mean: wh.mean.clone(),
        mixing: mix,
        unmixing: unmix,
        component_variance: order.iter().map(|&i| variance[i]).collect(),
        sources: None,
        used_frames: Vec::new(),
        report,
    };
    (out, canon)
}

/// Maps the rotation back to channel space: `M = E sqrt(Λ) Wᵀ`, `W_full = W Λ^{-1/2} Eᵀ`, with
/// zero rows/columns for dead channels.
fn to_channels(wh: &Whitener, w: &DMatrix<f64>) -> (DMatrix<f64>, DMatrix<f64>) {
    let (m, channels) = (wh.components(), wh.channels());
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
    (mixing, unmixing)
}

/// The sign and order convention (see the module docs of [`super`]).
fn canonical(mixing: &DMatrix<f64>, skewness: &[f64], frames: usize) -> Canonical {
    let m = mixing.ncols();
    let variance: Vec<f64> = mixing.column_iter().map(|c| c.norm_squared()).collect();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| variance[b].total_cmp(&variance[a]));
    let threshold = SKEW_SIGNIFICANT * (6.0 / frames.max(1) as f64).sqrt();
    let signs = (0..m)
        .map(|i| {
            let skew = skewness[i];
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
    Canonical { order, signs }
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
