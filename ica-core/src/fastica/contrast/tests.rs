use super::*;

#[test]
fn fast_exp_matches_std() {
    for k in 0..20_000 {
        let x = -60.0 + k as f64 * 0.006;
        let e = exp_fast(x.min(0.0));
        let want = x.min(0.0).exp();
        assert!(
            (e - want).abs() <= 1e-14 * want,
            "exp({x}) = {e}, want {want}"
        );
    }
}

#[test]
fn f32_tanh_is_within_1e6_of_std() {
    let mut worst = 0.0f64;
    for k in 0..400_001 {
        let x = -20.0 + k as f64 * 1e-4;
        let t = f64::from(tanh_f32(x as f32));
        worst = worst.max((t - x.tanh()).abs());
    }
    assert!(worst < 1e-6, "max |error| {worst}");
    assert_eq!(tanh_f32(f32::INFINITY), 1.0);
    assert_eq!(tanh_f32(f32::NEG_INFINITY), -1.0);
    assert_eq!(tanh_f32(0.0), 0.0);
}

#[test]
fn gaussian_expectations_match_known_values() {
    // E log cosh(nu) = 0.374567207491... (reference value, numerical integration).
    let lc = Contrast::LogCosh.gaussian_expectation();
    assert!((lc - 0.374_567_207_491).abs() < 1e-9, "{lc}");
    // The closed forms agree with the same quadrature.
    assert!((Contrast::Exp.gaussian_expectation() + 0.5f64.sqrt()).abs() < 1e-15);
}
