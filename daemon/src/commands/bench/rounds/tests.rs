use super::median_range;

/// The median of interleaved rounds ignores one drifting round, where a pooled ratio would not.
#[test]
fn the_median_of_the_rounds_ratios_and_their_range() {
    assert_eq!(median_range(vec![1.2, 3.0, 1.1]), (1.2, 1.1, 3.0));
    let (median, lo, hi) = median_range(vec![1.5, 1.0, 9.0, 1.25]);
    assert_eq!(
        (median, lo, hi),
        (1.375, 1.0, 9.0),
        "an even count: the middle two's mean"
    );
    assert!(median_range(vec![]).0.is_nan(), "no rounds: no ratio");
}
