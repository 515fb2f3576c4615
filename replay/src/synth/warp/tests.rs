use super::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

#[test]
fn random_warp_is_monotonic_pinned_and_not_uniform() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut non_uniform = 0;
    for _ in 0..50 {
        let w = Warp::random(&mut rng, 3.0, 120.0);
        let c = &w.canonical_s;
        assert_eq!(c[0], 0.0);
        assert!((w.canonical_duration_s() - 3.0).abs() < 1e-9);
        assert!(c.windows(2).all(|p| p[1] > p[0]));
        let scale = (w.n_frames() - 1) as f64 / 120.0 / 3.0;
        assert!((0.8..=1.2).contains(&scale), "scale {scale}");
        let f = w.frame_at(c[40] + 0.25 * (c[41] - c[40]));
        assert!((f - 40.25).abs() < 1e-9);
        let pace: Vec<f64> = c.windows(2).map(|p| p[1] - p[0]).collect();
        let max = pace.iter().cloned().fold(f64::MIN, f64::max);
        let min = pace.iter().cloned().fold(f64::MAX, f64::min);
        if max / min > 1.1 {
            non_uniform += 1;
        }
    }
    assert!(
        non_uniform >= 40,
        "only {non_uniform} of 50 warps vary their pace"
    );
}
