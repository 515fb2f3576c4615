//! The covariance spectrum for whitening: every eigenvalue (the report's scree and the variance
//! target need them all) but only the `m` leading eigenvectors, which is all whitening uses.
//!
//! A full `SymmetricEigen` of a 327 x 327 covariance spends most of its time accumulating all 327
//! eigenvectors. Here the eigenvalues come from the eigenvalue-only QR, and the leading vectors
//! from block subspace iteration with Rayleigh-Ritz (`p^2 l` flops a step). Since the spectrum is
//! known first, the block size and the number of steps are planned from the gap
//! `lambda_{l+1} / lambda_m`; when no block converges cheaply (a flat spectrum) or the residual
//! bound is not met in the planned steps, the full decomposition is used, so the vectors are
//! never less accurate than before.

use nalgebra::{DMatrix, SymmetricEigen};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::linalg::{mul_add, strided};

/// A Ritz vector is accepted when `|C v - theta v| <= RESIDUAL * lambda_1`: its angle to the
/// true eigenvector is then below `RESIDUAL * lambda_1 / gap`, far below sampling noise.
const RESIDUAL: f64 = 1e-12;
/// Planned steps above this make subspace iteration dearer than the full decomposition.
const MAX_STEPS: usize = 40;
/// Below this size the full decomposition costs next to nothing.
const MIN_DIM: usize = 48;
/// Fixed seed of the start block: the result depends on the covariance only.
const START_SEED: u64 = 0x5EED_0FE1_6E00;

/// All eigenvalues of the symmetric `cov`, largest first, negatives clamped to 0.
pub(crate) fn sorted_eigenvalues(cov: &DMatrix<f64>) -> Vec<f64> {
    let mut values: Vec<f64> = cov
        .symmetric_eigenvalues()
        .iter()
        .map(|&l| l.max(0.0))
        .collect();
    values.sort_by(|a, b| b.total_cmp(a));
    values
}

/// The `m` leading eigenpairs of `cov` given its sorted spectrum `values`: eigenvalues largest
/// first and the matching unit eigenvectors as columns (`p x m`).
pub(crate) fn leading(cov: &DMatrix<f64>, values: &[f64], m: usize) -> (Vec<f64>, DMatrix<f64>) {
    plan(values, m)
        .and_then(|(block, steps)| subspace(cov, values[0], m, block, steps))
        .unwrap_or_else(|| full(cov, m))
}

/// Block size and step budget for subspace iteration, or `None` when the full decomposition is
/// cheaper. The error of the `m`-th Ritz vector shrinks like `(lambda_{l+1} / lambda_m)^k`.
fn plan(values: &[f64], m: usize) -> Option<(usize, usize)> {
    let p = values.len();
    if p < MIN_DIM || m == 0 || values[m - 1] <= 0.0 {
        return None;
    }
    let target = RESIDUAL.ln();
    let mut best: Option<(usize, usize, usize)> = None;
    for block in (m + 2)..=(3 * m + 16).min(p / 2) {
        let rho = values[block] / values[m - 1];
        // Two extra steps absorb the start block's projection on the leading space.
        let steps = if rho <= 0.0 {
            2
        } else {
            (target / rho.ln()).ceil() as usize + 2
        };
        if steps > MAX_STEPS {
            continue;
        }
        let cost = block * steps;
        if best.is_none_or(|(_, _, c)| cost < c) {
            best = Some((block, steps, cost));
        }
    }
    // The eigenvector part of the full decomposition is several p^3 flops; a step is about
    // 2 p^2 l plus Rayleigh-Ritz, so `l k` should stay within a small multiple of `p`.
    best.filter(|&(_, _, cost)| cost < 2 * p)
        .map(|(block, steps, _)| (block, steps))
}

/// Block subspace iteration from a fixed random start; `None` if the residual bound is not met
/// within `steps` (plus slack), so the caller falls back to the full decomposition.
fn subspace(
    cov: &DMatrix<f64>,
    lambda1: f64,
    m: usize,
    block: usize,
    steps: usize,
) -> Option<(Vec<f64>, DMatrix<f64>)> {
    let p = cov.nrows();
    let mut rng = ChaCha8Rng::seed_from_u64(START_SEED);
    let start = DMatrix::from_fn(p, block, |_, _| StandardNormal.sample(&mut rng));
    let mut q = start.qr().q();
    let mut y = DMatrix::<f64>::zeros(p, block);
    let bound = RESIDUAL * lambda1;
    for _ in 0..(2 * steps + 4) {
        mul_add(&mut y, 1.0, cov, &q, 0.0);
        let mut h = DMatrix::<f64>::zeros(block, block);
        let qt = strided(q.as_slice(), block, p, p, 1);
        mul_add(&mut h, 1.0, &qt, &y, 0.0);
        h = (&h + h.transpose()) * 0.5;
        let eig = SymmetricEigen::new(h);
        let mut order: Vec<usize> = (0..block).collect();
        order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
        let u = DMatrix::from_fn(block, block, |r, c| eig.eigenvectors[(r, order[c])]);
        let vectors = &q * &u;
        let images = &y * &u;
        let theta: Vec<f64> = order.iter().map(|&i| eig.eigenvalues[i]).collect();
        let worst = (0..m)
            .map(|j| (images.column(j) - vectors.column(j) * theta[j]).norm())
            .fold(0.0, f64::max);
        if worst <= bound {
            let values = theta[..m].iter().map(|&t| t.max(0.0)).collect();
            return Some((values, vectors.columns(0, m).into_owned()));
        }
        q = images.qr().q();
    }
    None
}

/// The full decomposition's `m` leading eigenpairs.
fn full(cov: &DMatrix<f64>, m: usize) -> (Vec<f64>, DMatrix<f64>) {
    let eig = SymmetricEigen::new(cov.clone());
    let mut order: Vec<usize> = (0..eig.eigenvalues.len()).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let values = order[..m]
        .iter()
        .map(|&i| eig.eigenvalues[i].max(0.0))
        .collect();
    let vectors = DMatrix::from_fn(cov.nrows(), m, |r, c| eig.eigenvectors[(r, order[c])]);
    (values, vectors)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `p x p` covariance with `spikes` large eigenvalues over a decaying floor, in a random basis.
    fn covariance(p: usize, spikes: usize, floor_decay: f64) -> DMatrix<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let basis = DMatrix::<f64>::from_fn(p, p, |_, _| StandardNormal.sample(&mut rng))
            .qr()
            .q();
        let diag = DMatrix::<f64>::from_fn(p, p, |r, c| match (r == c, r < spikes) {
            (false, _) => 0.0,
            (true, true) => 100.0 / (1.0 + r as f64),
            (true, false) => floor_decay.powi(r as i32),
        });
        &basis * diag * basis.transpose()
    }

    fn assert_matches_full(cov: &DMatrix<f64>, m: usize) {
        let values = sorted_eigenvalues(cov);
        let (got_values, got) = leading(cov, &values, m);
        let (want_values, want) = full(cov, m);
        for j in 0..m {
            let rel = (got_values[j] - want_values[j]).abs() / want_values[0];
            assert!(
                rel < 1e-11,
                "eigenvalue {j}: {} vs {}",
                got_values[j],
                want_values[j]
            );
            let cos = got.column(j).dot(&want.column(j)).abs();
            assert!(1.0 - cos < 1e-9, "eigenvector {j}: |cos| = {cos}");
            assert!((values[j] - want_values[j]).abs() / want_values[0] < 1e-11);
        }
    }

    #[test]
    fn subspace_iteration_matches_full_decomposition_on_a_gapped_spectrum() {
        let cov = covariance(120, 8, 0.98);
        let values = sorted_eigenvalues(&cov);
        assert!(
            plan(&values, 8).is_some(),
            "a clear gap takes the fast path"
        );
        assert_matches_full(&cov, 8);
    }

    #[test]
    fn flat_spectrum_falls_back_to_the_full_decomposition() {
        let cov = covariance(120, 0, 0.999);
        let values = sorted_eigenvalues(&cov);
        assert!(plan(&values, 10).is_none(), "no gap: full decomposition");
        assert_matches_full(&cov, 10);
    }
}
