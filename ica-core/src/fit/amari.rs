//! The Amari index: how far `P = W_est A_true` is from a scaled permutation.

use nalgebra::DMatrix;

/// Normalised Amari index of a square matrix `P` (usually `W_est · A_true`, `m x m`):
///
/// ```text
///             1       m  ( m  |p_ij|          )     m  ( m  |p_ij|          )
/// AI = ---------- [  Σ   (  Σ  -------- - 1  )  +  Σ   (  Σ  -------- - 1  ) ]
///      2 m (m-1)    i=1  ( j=1 max_k|p_ik|    )    j=1  ( i=1 max_k|p_kj|    )
/// ```
///
/// Each row (column) term lies in `[0, m-1]`, so `AI` is in `[0, 1]`: 0 exactly when `P` is a
/// permutation times a diagonal scaling (perfect separation up to the ICA ambiguities), 1 when
/// every entry has the same magnitude. A 1 x 1 matrix scores 0. Scaling any row or column of `P`
/// leaves it unchanged, so unmixing rows of any scale compare fairly.
///
/// Returns `None` if `P` is not square, is empty, has a non-finite entry, or has an all-zero row
/// or column (no separation can be read from it).
///
/// ```
/// use ica_core::fit::amari_index;
/// use nalgebra::DMatrix;
/// let perm = DMatrix::from_row_slice(2, 2, &[0.0, -3.0, 2.0, 0.0]);
/// assert_eq!(amari_index(&perm), Some(0.0));
/// let flat = DMatrix::from_element(3, 3, 1.0);
/// assert_eq!(amari_index(&flat), Some(1.0));
/// ```
pub fn amari_index(p: &DMatrix<f64>) -> Option<f64> {
    let (rows, cols) = p.shape();
    if rows != cols || rows == 0 || p.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let m = rows;
    if m == 1 {
        return (p[(0, 0)] != 0.0).then_some(0.0);
    }
    let a = p.abs();
    let mut total = 0.0;
    for row in a.row_iter() {
        let max = row.max();
        if max == 0.0 {
            return None;
        }
        total += row.sum() / max - 1.0;
    }
    for col in a.column_iter() {
        let max = col.max();
        if max == 0.0 {
            return None;
        }
        total += col.sum() / max - 1.0;
    }
    Some(total / (2.0 * m as f64 * (m as f64 - 1.0)))
}
