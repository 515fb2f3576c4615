//! The covariance spectrum for whitening: every eigenvalue (the report's scree and the variance
//! target need them all) and the eigenvectors in the same order, from one symmetric
//! eigendecomposition by faer. On a 327 x 327 covariance it takes 20 ms, against 16 ms for
//! nalgebra's eigenvalues alone and 50 ms for its full decomposition, which a flat spectrum
//! (no gap after the kept components) needed on top.

use nalgebra::DMatrix;

use crate::input::FitError;

/// The symmetric `cov`'s eigenvalues, largest first, negatives clamped to 0, and the matching
/// unit eigenvectors as the columns of a `p x p` matrix.
///
/// # Errors
/// [`FitError::Eigendecomposition`] if it does not converge.
pub(crate) fn decompose(cov: &DMatrix<f64>) -> Result<(Vec<f64>, DMatrix<f64>), FitError> {
    let p = cov.nrows();
    let a = faer::Mat::<f64>::from_fn(p, p, |r, c| cov[(r, c)]);
    let eig = a
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|_| FitError::Eigendecomposition)?;
    let (s, u) = (eig.S().column_vector(), eig.U());
    let mut order: Vec<usize> = (0..p).collect();
    order.sort_by(|&a, &b| s[b].total_cmp(&s[a]));
    let values = order.iter().map(|&i| s[i].max(0.0)).collect();
    let vectors = DMatrix::from_fn(p, p, |r, c| u[(r, order[c])]);
    Ok((values, vectors))
}

#[cfg(test)]
mod tests;
