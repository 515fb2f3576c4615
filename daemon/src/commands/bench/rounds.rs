//! The interleaved rounds' ratios to the relay: one per round, then their median, so a host
//! drifting through the run (a build starting) does not decide the ratio.

use super::harness;

/// A round's p50 and p99 ratios, daemon over relay.
pub(super) fn ratios(daemon: &harness::Seen, relay: &harness::Seen) -> [f64; 2] {
    [0.5, 0.99].map(|q| {
        let r = relay.latency_us.value_at_quantile(q).max(1);
        daemon.latency_us.value_at_quantile(q) as f64 / r as f64
    })
}

/// The median of `values` (the mean of the middle two of an even count), and the range.
pub(super) fn median_range(mut values: Vec<f64>) -> (f64, f64, f64) {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n == 0 {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let median = (values[(n - 1) / 2] + values[n / 2]) / 2.0;
    (median, values[0], values[n - 1])
}

#[cfg(test)]
mod tests;
