use super::*;

fn times(rate: f64, n: usize, decimals: usize) -> Vec<(usize, f64)> {
    (0..n)
        .map(|i| {
            let text = format!("{:.*}", decimals, i as f64 / rate);
            (i + 2, text.parse().unwrap())
        })
        .collect()
}

#[test]
fn common_rates_come_back_exactly_from_rounded_times() {
    for (rate, n, dec) in [
        (120.0, 2, 6),
        (120.0, 500, 6),
        (60.0, 10, 5),
        (100.0, 3, 2),
        (30_000.0 / 1001.0, 2, 6),
        (120_000.0 / 1001.0, 1000, 6),
        (250.0, 40, 3),
    ] {
        let res = 10f64.powi(-(dec as i32));
        assert_eq!(
            derive_rate(&times(rate, n, dec), res).unwrap(),
            rate,
            "{rate} {n} {dec}"
        );
    }
}

#[test]
fn odd_rate_is_rounded_to_what_the_times_support() {
    // 1/0.0137 s = 72.99270... Hz; 4-decimal times over 100 frames pin it to +-0.0054 Hz,
    // so two decimals is the simplest rate they support.
    let t: Vec<(usize, f64)> = (0..100).map(|i| (i, i as f64 * 0.0137)).collect();
    assert_eq!(derive_rate(&t, 1e-4).unwrap(), 72.99);
    // Exponent-notation times carry no visible rounding: the estimate is kept to ~1e-9.
    let rate = derive_rate(&t, 0.0).unwrap();
    assert!((rate - 1.0 / 0.0137).abs() < 1e-6, "{rate}");
}

#[test]
fn too_few_frames_and_uneven_steps_are_errors() {
    assert!(matches!(
        derive_rate(&[], 1e-6),
        Err(ReadError::NoRate { frames: 0 })
    ));
    assert!(matches!(
        derive_rate(&[(2, 0.0)], 1e-6),
        Err(ReadError::NoRate { frames: 1 })
    ));
    let t = [(2, 0.0), (3, 0.01), (4, 0.05), (5, 0.06)];
    assert!(matches!(
        derive_rate(&t, 1e-6),
        Err(ReadError::UnevenTime { line: 4, .. })
    ));
    let still = [(2, 1.0), (3, 1.0)];
    assert!(matches!(
        derive_rate(&still, 1e-6),
        Err(ReadError::UnevenTime { line: 3, .. })
    ));
}

#[test]
fn decimals_of_time_cells() {
    assert_eq!(decimals("0.008333"), Some(6));
    assert_eq!(decimals("12"), Some(0));
    assert_eq!(decimals("8.3e-3"), None);
}
