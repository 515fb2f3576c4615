use super::*;
use nalgebra::SymmetricEigen;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

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

/// Same spectrum and, up to sign, the same leading axes as nalgebra's decomposition.
#[test]
fn matches_nalgebra_on_a_gapped_and_a_flat_spectrum() {
    for (spikes, decay) in [(8, 0.98), (0, 0.999)] {
        let cov = covariance(120, spikes, decay);
        let (values, vectors) = decompose(&cov).expect("converges");
        let want = SymmetricEigen::new(cov.clone());
        let mut order: Vec<usize> = (0..120).collect();
        order.sort_by(|&a, &b| want.eigenvalues[b].total_cmp(&want.eigenvalues[a]));
        assert!(values.windows(2).all(|w| w[0] >= w[1]), "largest first");
        for (j, &i) in order.iter().enumerate() {
            let rel = (values[j] - want.eigenvalues[i]).abs() / values[0];
            assert!(rel < 1e-12, "eigenvalue {j}: {rel:e}");
            let v = vectors.column(j);
            assert!((v.norm() - 1.0).abs() < 1e-12);
            // Axes of distinct eigenvalues are defined up to sign.
            let gap = [j.checked_sub(1), Some(j + 1)]
                .into_iter()
                .flatten()
                .filter(|&k| k < 120)
                .map(|k| (values[k] - values[j]).abs())
                .fold(f64::INFINITY, f64::min);
            if gap > 1e-6 * values[0] {
                let cos = v.dot(&want.eigenvectors.column(i)).abs();
                assert!(1.0 - cos < 1e-9, "eigenvector {j}: |cos| = {cos}");
            }
        }
    }
}
