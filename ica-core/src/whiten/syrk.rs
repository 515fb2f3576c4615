//! The triangular covariance update both whitening paths use: `cov[I, J] += X[I, :] X[J, :]^T`
//! for channel blocks `I <= J`, a blocked syrk on top of nalgebra's gemm (matrixmultiply).
//!
//! Only blocks on or above the diagonal are multiplied, which saves close to half the flops of
//! a full `X X^T`; the lower triangle is left stale for the caller to mirror once at the end.

use nalgebra::{DMatrix, DMatrixView, DMatrixViewMut};

use crate::linalg::{mul_add, strided};

/// `cov[I, J] += x[I, :] x[J, :]^T` for channel blocks `I <= J` of edge `block`.
///
/// `data` is `x`'s memory: `channels x frames`, column-major (one frame per column), and `x` is
/// the view of it.
///
/// # Panics
/// If `cov` is not `channels x channels` or `data` is shorter than `x` (internal invariants of
/// the callers).
pub(crate) fn accumulate_upper(
    cov: &mut DMatrix<f64>,
    data: &[f64],
    x: DMatrixView<'_, f64>,
    block: usize,
) {
    let (nl, frames) = x.shape();
    for i0 in (0..nl).step_by(block) {
        let bi = block.min(nl - i0);
        let a = x.rows(i0, bi);
        for j0 in (i0..nl).step_by(block) {
            let bj = block.min(nl - j0);
            // x[J, :]^T as a strided view of the same memory: no copy.
            let bt = strided(&data[j0..], frames, bj, nl, 1);
            let mut out: DMatrixViewMut<'_, f64> = cov.view_mut((i0, j0), (bi, bj));
            mul_add(&mut out, 1.0, &a, &bt, 1.0);
        }
    }
}

/// Copies the upper triangle of the square `m` into its lower triangle.
pub(crate) fn mirror_upper(m: &mut DMatrix<f64>) {
    let n = m.nrows();
    for j in 0..n {
        for i in (j + 1)..n {
            m[(i, j)] = m[(j, i)];
        }
    }
}

/// `m[i, j] += scale d_i d_j` for `i <= j`.
pub(crate) fn rank_one_upper(m: &mut DMatrix<f64>, d: &[f64], scale: f64) {
    for (j, &dj) in d.iter().enumerate() {
        let s = scale * dj;
        let col = &mut m.as_mut_slice()[j * d.len()..j * d.len() + j + 1];
        for (v, &di) in col.iter_mut().zip(d) {
            *v += s * di;
        }
    }
}
