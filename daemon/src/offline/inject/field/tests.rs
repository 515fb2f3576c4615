use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::*;

#[test]
fn the_field_has_its_rms_on_the_face_and_leaves_the_head_still() {
    let rest: Vec<[f64; 3]> = (0..40)
        .map(|i| {
            let t = f64::from(i) * 0.3;
            [60.0 * t.cos(), 80.0 * t.sin(), 10.0 * (2.0 * t).cos()]
        })
        .collect();
    let head = [0, 1, 2];
    let field = smooth_field(&rest, &head, 3.0, &mut ChaCha8Rng::seed_from_u64(7));
    let face_ss: f64 = field[9..].iter().map(|v| v * v).sum();
    assert!(((face_ss / 37.0).sqrt() - 3.0).abs() < 1e-9);
    assert!(field[..9].iter().all(|&v| v == 0.0));
    let other = smooth_field(&rest, &head, 3.0, &mut ChaCha8Rng::seed_from_u64(8));
    assert_ne!(field, other, "the seed draws the field");
}
