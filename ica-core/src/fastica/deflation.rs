//! The deflationary FastICA update: one component at a time, each kept orthogonal to the ones
//! already found by Gram-Schmidt. Slower than the symmetric update and order-dependent (errors
//! accumulate in later components), offered for comparison and for data where the symmetric
//! update oscillates.

use nalgebra::{DMatrix, DVector};

use super::{Contrast, Outcome};

/// Runs the one-unit update for each row of `w0` in turn. `iterations` is the largest count of
/// any component, `converged` is whether all did, `last_delta` the largest final change.
pub(crate) fn run(
    z: &DMatrix<f64>,
    w0: &DMatrix<f64>,
    contrast: Contrast,
    tol: f64,
    max_iter: usize,
) -> Outcome {
    let (m, frames) = z.shape();
    let inv_t = 1.0 / frames as f64;
    let mut w = DMatrix::<f64>::zeros(m, m);
    let mut y = DVector::<f64>::zeros(frames);
    let mut next = DVector::<f64>::zeros(m);
    let (mut iterations, mut converged, mut last_delta) = (0, true, 0.0f64);
    for p in 0..m {
        let mut v: DVector<f64> = w0.row(p).transpose();
        orthonormalise(&mut v, &w, p);
        let mut delta = f64::INFINITY;
        let mut it = 0;
        while it < max_iter {
            it += 1;
            y.gemv_tr(1.0, z, &v, 0.0);
            let gp = contrast.apply(y.as_mut_slice()) * inv_t;
            next.gemv(inv_t, z, &y, 0.0);
            next.axpy(-gp, &v, 1.0);
            orthonormalise(&mut next, &w, p);
            delta = (1.0 - next.dot(&v).abs()).abs();
            std::mem::swap(&mut v, &mut next);
            if delta < tol {
                break;
            }
        }
        iterations = iterations.max(it);
        converged &= delta < tol;
        last_delta = last_delta.max(delta);
        w.row_mut(p).copy_from(&v.transpose());
    }
    Outcome {
        w,
        iterations,
        converged,
        last_delta,
    }
}

/// Removes the projections on the first `p` rows of `w` and normalises to unit length.
pub(crate) fn orthonormalise(v: &mut DVector<f64>, w: &DMatrix<f64>, p: usize) {
    for j in 0..p {
        let row = w.row(j);
        let c = row.dot(&v.transpose());
        for (x, r) in v.iter_mut().zip(row.iter()) {
            *x -= c * r;
        }
    }
    let norm = v.norm();
    // Rows of a random start are independent with probability one; the guard keeps a
    // pathological start finite instead of dividing by zero.
    if norm > f64::MIN_POSITIVE {
        *v /= norm;
    }
}
