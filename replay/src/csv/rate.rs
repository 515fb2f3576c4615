//! Deriving a frame rate from a CSV time column, which is all a plain CSV says about time.

use crate::error::ReadError;

/// Rates of the NTSC family (x/1.001) that no short decimal rounding reaches.
const FRACTIONAL_RATES_HZ: [f64; 4] = [
    24_000.0 / 1001.0,
    30_000.0 / 1001.0,
    60_000.0 / 1001.0,
    120_000.0 / 1001.0,
];

/// Derives the frame rate from `(line, time_s)` of consecutive frames.
///
/// The estimate is `(n - 1) / (t_last - t_first)`: frame numbers are already checked to be
/// consecutive, so the mean step is exact up to the rounding of the two end times, an error that
/// shrinks as the take grows (a median of rounded steps would keep the full rounding error: at
/// 120 Hz with 6 decimals, 0.008333 s reads as 120.005 Hz). That rounding, `resolution_s` (the
/// time column's last decimal place), bounds how far the estimate may be from the true rate; the
/// result is the simplest rate within that bound: an integer, an NTSC x/1.001 rate, or the
/// estimate rounded to the fewest decimals (up to 6), else the estimate itself.
///
/// # Errors
/// [`ReadError::NoRate`] for fewer than two frames; [`ReadError::UnevenTime`] when time does not
/// increase or a step is outside 0.5-1.5x the mean step (a time column in other units, dropped
/// frames or a shuffled file would otherwise yield a plausible but wrong rate).
pub(crate) fn derive_rate(times: &[(usize, f64)], resolution_s: f64) -> Result<f64, ReadError> {
    let (Some(&(_, first)), Some(&(_, last))) = (times.first(), times.last()) else {
        return Err(ReadError::NoRate { frames: 0 });
    };
    if times.len() < 2 {
        return Err(ReadError::NoRate { frames: 1 });
    }
    let span = last - first;
    let mean_step_s = span / (times.len() - 1) as f64;
    for pair in times.windows(2) {
        let step_s = pair[1].1 - pair[0].1;
        let even = mean_step_s > 0.0 && step_s >= 0.5 * mean_step_s && step_s <= 1.5 * mean_step_s;
        if !even {
            return Err(ReadError::UnevenTime {
                line: pair[1].0,
                step_s,
                mean_step_s,
            });
        }
    }
    let estimate = 1.0 / mean_step_s;
    // Each end time is off by at most half a resolution step; a tiny relative slack absorbs the
    // binary representation of the decimal times.
    let tolerance = estimate * (resolution_s / span) + estimate * 1e-9;
    Ok(simplest_rate(estimate, tolerance))
}

/// The simplest rate within `tolerance` of `estimate`.
fn simplest_rate(estimate: f64, tolerance: f64) -> f64 {
    let near = |r: f64| r > 0.0 && (r - estimate).abs() <= tolerance;
    let whole = estimate.round();
    if near(whole) {
        return whole;
    }
    if let Some(&r) = FRACTIONAL_RATES_HZ.iter().find(|&&r| near(r)) {
        return r;
    }
    for decimals in 1..=6 {
        let scale = 10f64.powi(decimals);
        let rounded = (estimate * scale).round() / scale;
        if near(rounded) {
            return rounded;
        }
    }
    estimate
}

/// Digits after the decimal point of a time cell, `None` for exponent notation (whose resolution
/// is not visible in the text).
pub(crate) fn decimals(cell: &str) -> Option<u32> {
    let cell = cell.trim();
    if cell.contains(['e', 'E']) {
        return None;
    }
    let digits = cell.split_once('.').map_or(0, |(_, frac)| frac.len());
    u32::try_from(digits).ok()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // a failed unwrap is a failed test
mod tests;
