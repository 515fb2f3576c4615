//! Matrix products on column-major slices, through faer (the `gemm` crate's kernels).
//!
//! faer replaced nalgebra's gemm (matrixmultiply) here: on a Zen 1 core it took the whitening
//! pass from 23.2 to 15.0 ms per 10,000 frames of 327 channels (`cargo bench -p ica-core --bench
//! stream`), and it needs no plain-loop fallback for small shapes or transposed views.

use faer::{Accum, MatMut, MatRef, Par};

/// `rows x cols` view of `data`, column-major (element `(i, j)` at `i + j * rows`).
///
/// # Panics
/// If `data` is shorter than `rows * cols` (an internal invariant of the callers).
pub(crate) fn cols(data: &[f64], rows: usize, cols: usize) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(&data[..rows * cols], rows, cols)
}

/// The mutable [`cols`].
pub(crate) fn cols_mut(data: &mut [f64], rows: usize, cols: usize) -> MatMut<'_, f64> {
    MatMut::from_column_major_slice_mut(&mut data[..rows * cols], rows, cols)
}

/// `out = a b`, on the calling thread.
///
/// # Panics
/// On mismatched shapes (an internal invariant of the callers).
pub(crate) fn product(out: MatMut<'_, f64>, a: MatRef<'_, f64>, b: MatRef<'_, f64>) {
    faer::linalg::matmul::matmul(out, Accum::Replace, a, b, 1.0, Par::Seq);
}

/// `out -= a b`, on the calling thread.
///
/// # Panics
/// On mismatched shapes (an internal invariant of the callers).
pub(crate) fn subtract_product(out: MatMut<'_, f64>, a: MatRef<'_, f64>, b: MatRef<'_, f64>) {
    faer::linalg::matmul::matmul(out, Accum::Add, a, b, -1.0, Par::Seq);
}
