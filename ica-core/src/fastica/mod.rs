//! FastICA (Hyvärinen 1999) on whitened data, with seeded restarts.
//!
//! The input is the `m x T` whitened matrix `Z` from [`crate::whiten`]; the output is an
//! orthogonal `m x m` rotation `W` with `u = W z` as independent as the contrast can make them.
//! Each restart draws its start from a ChaCha8 stream seeded with
//! `seed + k * 0x9E37_79B9_7F4A_7C15` (restart `k`, wrapping), so results depend on the seed
//! only: there are no threads and no clock.
//!
//! For data too long to hold, the same iteration runs one pass over the data per step:
//! [`UpdateAccumulator`] (map/merge sums of a step), [`Refiner`] (the pass-by-pass state
//! machine), [`SourceMoments`] (negentropy and skewness of the result) and [`Subsample`] (the
//! restarts' subsample, collected while streaming).

mod chunked;
mod contrast;
mod deflation;
mod fused;
mod refine;
mod subsample;
mod symmetric;

pub use chunked::{SourceMoments, Update, UpdateAccumulator};
pub use contrast::Contrast;
pub use refine::{refine_chunked, ChunkSink, RefineOutcome, RefineSettings, Refiner};
pub use subsample::{Subsample, SubsamplePlan};

use nalgebra::DMatrix;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::{Refinement, RestartReport};

/// The update rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Algorithm {
    /// All components at once, re-orthogonalised symmetrically each step (the default).
    #[default]
    Symmetric,
    /// One component at a time with Gram-Schmidt against the earlier ones.
    Deflation,
}

impl Algorithm {
    /// Name as written in the training report: `symmetric` or `deflation`.
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::Symmetric => "symmetric",
            Algorithm::Deflation => "deflation",
        }
    }
}

/// Odd multiplier of the golden ratio: spreads restart seeds across the u64 range.
const RESTART_SEED_STEP: u64 = 0x9E37_79B9_7F4A_7C15;

/// Seed of restart `k` derived from the base seed.
pub fn restart_seed(seed: u64, k: usize) -> u64 {
    seed.wrapping_add((k as u64).wrapping_mul(RESTART_SEED_STEP))
}

/// What one run of the update ended with.
#[derive(Debug)]
pub(crate) struct Outcome {
    pub w: DMatrix<f64>,
    pub iterations: usize,
    pub converged: bool,
    pub last_delta: f64,
}

/// Settings of the iteration (checked by the caller).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Settings {
    pub contrast: Contrast,
    pub algorithm: Algorithm,
    pub tol: f64,
    pub max_iter: usize,
    pub seed: u64,
    pub restarts: usize,
}

/// The kept rotation and every restart's diagnostics.
#[derive(Debug)]
pub(crate) struct IcaRun {
    /// Orthogonal `m x m` rotation of the whitened data.
    pub w: DMatrix<f64>,
    /// The kept solution's sources, `T x m` (one component per column).
    pub sources: DMatrix<f64>,
    pub restarts: Vec<RestartReport>,
    pub best: usize,
    /// Every restart's rotation, in run order (the best one before refinement).
    pub restart_w: Vec<DMatrix<f64>>,
}

/// Restarts explore about this many frames when the take is long enough (see `run`).
pub const EXPLORE_FRAMES: usize = 2500;

/// Column stride of the exploration subsample: 1 (no subsample) for a single restart or a take
/// shorter than twice [`EXPLORE_FRAMES`].
fn explore_stride(frames: usize, restarts: usize) -> usize {
    if restarts < 2 || frames < 2 * EXPLORE_FRAMES {
        1
    } else {
        frames / EXPLORE_FRAMES
    }
}

/// Runs `restarts` seeded restarts on `z` (`m x T`) and keeps the best.
///
/// "Best" is the largest total negentropy approximation `sum_i (E G(u_i) - E G(nu))^2` among the
/// converged restarts; only when none converged does it fall back to all of them, since an
/// unconverged rotation may stop half-way between two separations. Ties keep the earlier one.
///
/// On a long take the restarts only choose the basin: they run on every `k`-th frame (about
/// [`EXPLORE_FRAMES`] frames), and the winner alone is refined on all frames from its solution,
/// which takes a few iterations instead of a full run per restart. The winner's report carries
/// the refinement.
pub(crate) fn run(z: &DMatrix<f64>, s: Settings) -> IcaRun {
    let (m, frames) = z.shape();
    let stride = explore_stride(frames, s.restarts);
    if stride == 1 {
        return explore(z, s);
    }
    let cols: Vec<usize> = (0..frames).step_by(stride).collect();
    let sub = z.select_columns(&cols);
    let mut explored = explore(&sub, s);
    let mut ws = symmetric::Workspace::new(m, frames);
    let out = solve(z, explored.w.clone(), s, &mut ws);
    let negentropy = negentropy(&out.w, z, s.contrast, &mut ws.gy);
    explored.restarts[explored.best].refinement = Some(Refinement {
        frames,
        iterations: out.iterations,
        converged: out.converged,
        last_delta: out.last_delta,
        negentropy,
    });
    IcaRun {
        w: out.w,
        sources: ws.gy,
        restarts: explored.restarts,
        best: explored.best,
        restart_w: explored.restart_w,
    }
}

/// One run of the configured update from `w0`.
fn solve(
    z: &DMatrix<f64>,
    w0: DMatrix<f64>,
    s: Settings,
    ws: &mut symmetric::Workspace,
) -> Outcome {
    match s.algorithm {
        Algorithm::Symmetric => symmetric::run(z, w0, s.contrast, s.tol, s.max_iter, ws),
        Algorithm::Deflation => deflation::run(z, &w0, s.contrast, s.tol, s.max_iter),
    }
}

/// Total negentropy of the sources `W z`, which are left in `gy` (`T x m`).
fn negentropy(
    w: &DMatrix<f64>,
    z: &DMatrix<f64>,
    contrast: Contrast,
    gy: &mut DMatrix<f64>,
) -> f64 {
    let gaussian = contrast.gaussian_expectation();
    symmetric::sources_into(z, w, gy);
    gy.as_slice()
        .chunks_exact(z.ncols())
        .map(|col| contrast.negentropy(col, gaussian))
        .sum()
}

/// The seeded restarts on `z`, each from its own random start; keeps the best (see [`run`]).
pub(crate) fn explore(z: &DMatrix<f64>, s: Settings) -> IcaRun {
    use rayon::prelude::*;
    let (m, frames) = z.shape();
    // Each restart on its own workspace, at once on the caller's rayon pool; the choice below
    // reads them in run order, so the result does not depend on the thread count.
    let runs: Vec<(Outcome, f64, DMatrix<f64>)> = (0..s.restarts)
        .into_par_iter()
        .map(|k| {
            let mut ws = symmetric::Workspace::new(m, frames);
            let out = solve(z, random_start(m, restart_seed(s.seed, k)), s, &mut ws);
            let negentropy = negentropy(&out.w, z, s.contrast, &mut ws.gy);
            (out, negentropy, ws.gy)
        })
        .collect();
    let mut best: Option<(usize, f64)> = None;
    let mut reports = Vec::with_capacity(s.restarts);
    for (k, (out, negentropy, _)) in runs.iter().enumerate() {
        reports.push(RestartReport {
            seed: restart_seed(s.seed, k),
            iterations: out.iterations,
            converged: out.converged,
            last_delta: out.last_delta,
            negentropy: *negentropy,
            frames,
            refinement: None,
        });
        let better = match best {
            None => true,
            Some((b, score)) => {
                let (b_conv, conv) = (reports[b].converged, out.converged);
                (conv && !b_conv) || (conv == b_conv && *negentropy > score)
            }
        };
        if better {
            best = Some((k, *negentropy));
        }
    }
    let (best, _) = best.expect("restarts >= 1 is checked before fitting");
    let mut restart_w = Vec::with_capacity(s.restarts);
    let mut kept = None;
    for (k, (out, _, sources)) in runs.into_iter().enumerate() {
        if k == best {
            kept = Some((out.w.clone(), sources));
        }
        restart_w.push(out.w);
    }
    let (w, sources) = kept.expect("the best restart is one of them");
    IcaRun {
        w,
        sources,
        restarts: reports,
        best,
        restart_w,
    }
}

/// Stability of each row of `kept` across the other restarts, in the manner of ICASSO: for
/// each other restart, the best-matching |correlation| of the component with any of that
/// restart's components, averaged over the restarts. On whitened data the correlation of
/// `w_i·z` and `v_j·z` is `w_i·v_j` (unit rows), so no data pass is needed. Empty with a single
/// restart.
pub(crate) fn stability(kept: &DMatrix<f64>, restarts: &[DMatrix<f64>], best: usize) -> Vec<f64> {
    let others: Vec<&DMatrix<f64>> = restarts
        .iter()
        .enumerate()
        .filter(|(k, _)| *k != best)
        .map(|(_, w)| w)
        .collect();
    if others.is_empty() {
        return Vec::new();
    }
    let unit = |w: &DMatrix<f64>| {
        let mut w = w.clone();
        for mut row in w.row_iter_mut() {
            let n = row.norm();
            if n > 0.0 {
                row /= n;
            }
        }
        w
    };
    let kept = unit(kept);
    let mut sum = vec![0.0; kept.nrows()];
    for w in &others {
        let c = &kept * unit(w).transpose();
        for (i, row) in c.row_iter().enumerate() {
            sum[i] += row.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        }
    }
    sum.iter().map(|s| s / others.len() as f64).collect()
}

/// A standard-normal `m x m` start drawn from the restart's seed (rows are orthonormalised by the
/// update itself).
pub(crate) fn random_start(m: usize, seed: u64) -> DMatrix<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    DMatrix::from_fn(m, m, |_, _| StandardNormal.sample(&mut rng))
}
