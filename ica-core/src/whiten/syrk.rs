//! The triangular covariance update both whitening paths use: `cov += X Xᵀ`, upper triangle
//! only, by faer's triangular matrix product.
//!
//! Only the upper triangle (diagonal included) is computed, which saves close to half the flops
//! of a full `X Xᵀ`; the lower triangle is left stale for the caller to mirror once at the end.
//! faer's kernels (the `gemm` crate) beat the channel-blocked nalgebra gemm this replaced by 43 %
//! at 327 channels (`cargo bench -p ica-core --bench stream -- moments`: 124 → 71 ms per
//! 10,000 frames on a Zen 1 core). Each entry is still one sum over the block's frames in
//! order, added to the total: the models came out byte-identical on every layout of
//! `scripts/bench-train`.

use faer::linalg::matmul::triangular::{matmul, BlockStructure};
use faer::{Accum, Par};
use nalgebra::DMatrix;

use crate::linalg::{cols, cols_mut};

/// `cov[upper] += x xᵀ`, where `x` is `data` read as `channels x frames`, column-major (one
/// frame per column) and `channels` is `cov`'s edge.
///
/// # Panics
/// If `cov` is not square or `data` is not a whole number of its columns (internal invariants
/// of the callers).
pub(crate) fn accumulate_upper(cov: &mut DMatrix<f64>, data: &[f64]) {
    let channels = cov.nrows();
    assert_eq!(cov.ncols(), channels, "a square covariance");
    assert_eq!(data.len() % channels.max(1), 0, "whole frames");
    let frames = data.len() / channels.max(1);
    let x = cols(data, channels, frames);
    matmul(
        cols_mut(cov.as_mut_slice(), channels, channels),
        BlockStructure::TriangularUpper,
        Accum::Add,
        x,
        BlockStructure::Rectangular,
        x.transpose(),
        BlockStructure::Rectangular,
        1.0,
        Par::Seq,
    );
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
