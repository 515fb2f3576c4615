//! Matrix products on strided views, through nalgebra's gemm (matrixmultiply) when it applies.
//!
//! nalgebra only hands products to matrixmultiply when every dimension exceeds 5; its fallback
//! for smaller shapes assumes unit row strides and breaks on the transposed views used here, so
//! small shapes take a plain loop instead.

use nalgebra::{Dim, Dyn, Matrix, MatrixView, Storage, StorageMut};

/// A dynamic view with arbitrary strides (a transposed matrix without a copy).
pub(crate) type StridedView<'a> = MatrixView<'a, f64, Dyn, Dyn, Dyn, Dyn>;

/// `rows x cols` view of `data` with element `(i, j)` at `i * rstride + j * cstride`.
///
/// # Panics
/// If `data` is too short for the shape and strides (an internal invariant of the callers).
pub(crate) fn strided(
    data: &[f64],
    rows: usize,
    cols: usize,
    rstride: usize,
    cstride: usize,
) -> StridedView<'_> {
    StridedView::from_slice_with_strides_generic(
        data,
        Dyn(rows),
        Dyn(cols),
        Dyn(rstride),
        Dyn(cstride),
    )
}

/// Side above which nalgebra's gemm goes to matrixmultiply (see the module docs).
const GEMM_MIN_DIM: usize = 6;

/// `y = alpha a b + beta y`.
///
/// # Panics
/// On mismatched shapes (an internal invariant of the callers).
pub(crate) fn mul_add<R, C, SY, R2, C2, SA, R3, C3, SB>(
    y: &mut Matrix<f64, R, C, SY>,
    alpha: f64,
    a: &Matrix<f64, R2, C2, SA>,
    b: &Matrix<f64, R3, C3, SB>,
    beta: f64,
) where
    R: Dim,
    C: Dim,
    R2: Dim,
    C2: Dim,
    R3: Dim,
    C3: Dim,
    SY: StorageMut<f64, R, C>,
    SA: Storage<f64, R2, C2>,
    SB: Storage<f64, R3, C3>,
    nalgebra::constraint::ShapeConstraint: nalgebra::constraint::SameNumberOfRows<R, R2>
        + nalgebra::constraint::SameNumberOfColumns<C, C3>
        + nalgebra::constraint::AreMultipliable<R2, C2, R3, C3>,
{
    let (rows, cols) = y.shape();
    let inner = a.ncols();
    assert_eq!(
        (a.nrows(), b.nrows(), b.ncols()),
        (rows, inner, cols),
        "gemm shapes"
    );
    if rows >= GEMM_MIN_DIM && cols >= GEMM_MIN_DIM && inner >= GEMM_MIN_DIM {
        y.gemm(alpha, a, b, beta);
        return;
    }
    for j in 0..cols {
        for i in 0..rows {
            let mut acc = 0.0;
            for k in 0..inner {
                acc += a[(i, k)] * b[(k, j)];
            }
            let old = if beta == 0.0 { 0.0 } else { beta * y[(i, j)] };
            y[(i, j)] = alpha * acc + old;
        }
    }
}
