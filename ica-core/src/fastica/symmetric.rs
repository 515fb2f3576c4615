//! The symmetric (parallel) FastICA update and symmetric decorrelation.
//!
//! Layout: the whitened data `Z` is `m x T`, column-major (one frame per column). Each iteration
//! computes `Y^T = Z^T W^T` (`T x m`, so every component is one contiguous column the contrast
//! runs over), then `B = Z g(Y)^T` and `W+ = B^T / T - diag(E g'(y)) W`, all by gemm on strided
//! views: no transposed copies, no allocation inside the loop.

use nalgebra::{DMatrix, SymmetricEigen};

use super::{Contrast, Outcome};
use crate::linalg::{cols, cols_mut, product};

/// Buffers reused by every iteration of one fit.
#[derive(Debug)]
pub(crate) struct Workspace {
    /// `g(Y)^T`, `T x m`.
    pub gy: DMatrix<f64>,
    /// `Z g(Y)^T`, `m x m`.
    b: DMatrix<f64>,
    /// Mean `g'` per component.
    gp: Vec<f64>,
}

impl Workspace {
    pub(crate) fn new(m: usize, frames: usize) -> Self {
        Self {
            gy: DMatrix::zeros(frames, m),
            b: DMatrix::zeros(m, m),
            gp: vec![0.0; m],
        }
    }
}

/// `out = Z^T W^T` (`T x m`): the components' time series, one per column.
pub(crate) fn sources_into(z: &DMatrix<f64>, w: &DMatrix<f64>, out: &mut DMatrix<f64>) {
    let ((m, frames), k) = (z.shape(), w.nrows());
    product(
        cols_mut(out.as_mut_slice(), frames, k),
        cols(z.as_slice(), m, frames).transpose(),
        cols(w.as_slice(), k, m).transpose(),
    );
}

/// Step-size control: full steps first, as converging runs finish in a few dozen iterations;
/// a run still going after [`FIRST_HALVING`] iterations is usually cycling or chaotic (common
/// with sub-Gaussian or multimodal sources such as a held emotion level, where the full step
/// overshoots), so the step is halved then, and again at twice and four times that count, down
/// to [`MIN_STEP`]. A damped step keeps the same fixed points. (Hyvärinen's `fastica.m` also
/// halves the step on 2-cycles for one iteration; here that created cycles of its own.)
#[derive(Debug, Clone)]
pub(crate) struct StepControl {
    pub(crate) mu: f64,
    next_halving: usize,
}

/// Iterations before the first permanent halving of the step; later halvings follow at 2x, 4x...
const FIRST_HALVING: usize = 40;
/// The step is never halved below this.
const MIN_STEP: f64 = 0.1;

impl StepControl {
    pub(crate) fn new() -> Self {
        Self {
            mu: 1.0,
            next_halving: FIRST_HALVING,
        }
    }

    /// Adapts the step after iteration `it` (1-based).
    pub(crate) fn after(&mut self, it: usize) {
        if it >= self.next_halving && self.mu > MIN_STEP {
            self.next_halving *= 2;
            self.mu = (self.mu * 0.5).max(MIN_STEP);
        }
    }
}

/// `max_i |1 - |<a_i, b_i>||` over rows: 0 when every row of `a` is parallel to that of `b`.
fn row_change(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (0..a.nrows())
        .map(|i| (1.0 - a.row(i).dot(&b.row(i)).abs()).abs())
        .fold(0.0, f64::max)
}

/// Runs the symmetric update from `w` until `max |1 - |diag(W+ W^T)|| < tol` or `max_iter`.
///
/// The step is the classic `w_i+ = E{z g(y_i)} - E{g'(y_i)} w_i`, damped by [`StepControl`] when
/// the iteration cycles.
pub(crate) fn run(
    z: &DMatrix<f64>,
    mut w: DMatrix<f64>,
    contrast: Contrast,
    tol: f64,
    max_iter: usize,
    ws: &mut Workspace,
) -> Outcome {
    let (m, frames) = z.shape();
    let inv_t = 1.0 / frames as f64;
    decorrelate(&mut w);
    let mut w_new = DMatrix::<f64>::zeros(m, m);
    let mut step = StepControl::new();
    let mut delta = f64::INFINITY;
    for it in 1..=max_iter {
        sources_into(z, &w, &mut ws.gy);
        for (gp, col) in ws
            .gp
            .iter_mut()
            .zip(ws.gy.as_mut_slice().chunks_exact_mut(frames))
        {
            *gp = contrast.apply(col) * inv_t;
        }
        product(
            cols_mut(ws.b.as_mut_slice(), m, m),
            cols(z.as_slice(), m, frames),
            cols(ws.gy.as_slice(), frames, m),
        );
        delta = next_rotation(&w, &ws.b, &ws.gp, inv_t, step.mu, &mut w_new);
        std::mem::swap(&mut w, &mut w_new);
        if delta < tol {
            return Outcome {
                w,
                iterations: it,
                converged: true,
                last_delta: delta,
            };
        }
        step.after(it);
    }
    Outcome {
        w,
        iterations: max_iter,
        converged: false,
        last_delta: delta,
    }
}

/// One symmetric step from the pass's sums: `next = B^T / T - diag(E g') W` (rows `i` of `W`,
/// `B = Σ z g(y)^T`, `gp[i] = E g'(y_i)`), damped by `mu` when below 1, then decorrelated.
/// Returns the change `max |1 - |diag(next W^T)||`. Shared by the in-memory run and the
/// chunked [`super::Refiner`], so both take the same step from the same sums.
pub(crate) fn next_rotation(
    w: &DMatrix<f64>,
    b: &DMatrix<f64>,
    gp: &[f64],
    inv_t: f64,
    mu: f64,
    next: &mut DMatrix<f64>,
) -> f64 {
    for i in 0..w.nrows() {
        for j in 0..w.ncols() {
            next[(i, j)] = b[(j, i)] * inv_t - gp[i] * w[(i, j)];
        }
    }
    if mu < 1.0 {
        damp(next, w, mu);
    }
    decorrelate(next);
    row_change(next, w)
}

/// Replaces each row of `next` by the normalised blend `(1 - mu) w_i + mu n_i`, where `n_i` is
/// the row normalised and signed to agree with `w_i` (the classic step flips sub-Gaussian rows,
/// and a blend with a flipped row would cancel instead of damping).
fn damp(next: &mut DMatrix<f64>, w: &DMatrix<f64>, mu: f64) {
    for i in 0..w.nrows() {
        let norm = next.row(i).norm();
        if norm <= f64::MIN_POSITIVE {
            continue;
        }
        let sign = if next.row(i).dot(&w.row(i)) < 0.0 {
            -1.0
        } else {
            1.0
        };
        for j in 0..w.ncols() {
            next[(i, j)] = (1.0 - mu) * w[(i, j)] + mu * sign * next[(i, j)] / norm;
        }
    }
}

/// Symmetric decorrelation `W <- (W W^T)^{-1/2} W`, through the eigendecomposition of the small
/// `m x m` matrix `W W^T`; makes the rows orthonormal without favouring any of them.
pub(crate) fn decorrelate(w: &mut DMatrix<f64>) {
    let s = &*w * w.transpose();
    let eig = SymmetricEigen::new(s);
    let e = &eig.eigenvectors;
    // Eigenvalues of a Gram matrix are >= 0; the floor only keeps a degenerate W finite.
    let inv_sqrt = eig
        .eigenvalues
        .map(|d| 1.0 / d.max(f64::MIN_POSITIVE).sqrt());
    let mut scaled = e.clone();
    for (j, mut col) in scaled.column_iter_mut().enumerate() {
        col *= inv_sqrt[j];
    }
    let root = scaled * e.transpose();
    *w = root * &*w;
}
