//! What counts as a glitch: a marker faster than a speed limit (set from the data unless
//! given), or outside its learned plausible ball.

use ica_core::model::MarkerBounds;
use ica_core::robust::quantile;

use crate::offline::ModelFrames;

/// Multiple of the 99.9th percentile speed that marks a glitch when the limit is automatic.
pub const AUTO_SPEED_FACTOR: f64 = 4.0;
/// Floor of the automatic speed limit (mm/s): faces do not move faster than this in a frame.
pub const MIN_AUTO_SPEED_MM_S: f64 = 500.0;

/// Radius of a marker's plausible ball: this multiple of the 99th percentile of its distance
/// from its median position…
pub const BOUNDS_FACTOR: f64 = 2.0;
/// …but never below this (mm), so a nearly still marker keeps room for real motion.
pub const MIN_BOUNDS_MM: f64 = 15.0;

/// Per-marker ball: centre at the median position, radius [`BOUNDS_FACTOR`] × the 99th
/// percentile distance from it, at least [`MIN_BOUNDS_MM`]. Medians and percentiles ignore the
/// rare glitches they are meant to catch.
pub(super) fn marker_bounds(xyz: &[f32], missing: &[bool], n: usize) -> MarkerBounds {
    use rayon::prelude::*;
    let frames = missing.len() / n.max(1);
    // Markers at once on the current rayon pool; each marker's numbers are its own.
    let (centre, radius_mm) = (0..n)
        .into_par_iter()
        .map(|m| {
            let present: Vec<usize> = (0..frames).filter(|&f| !missing[f * n + m]).collect();
            let mut values = Vec::with_capacity(present.len());
            let mut c = [0.0f64; 3];
            for (a, slot) in c.iter_mut().enumerate() {
                values.clear();
                values.extend(present.iter().map(|&f| f64::from(xyz[(f * n + m) * 3 + a])));
                *slot = quantile(&mut values, 0.5);
            }
            values.clear();
            values.extend(present.iter().map(|&f| {
                (0..3)
                    .map(|a| (f64::from(xyz[(f * n + m) * 3 + a]) - c[a]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            }));
            let r = quantile(&mut values, 0.99) * BOUNDS_FACTOR;
            (c, r.max(MIN_BOUNDS_MM))
        })
        .unzip();
    MarkerBounds { centre, radius_mm }
}

/// [`AUTO_SPEED_FACTOR`] × the 99.9th percentile of per-frame marker speeds (mm/s), over
/// frames concatenated take after take (`frames` gives the take boundaries).
pub(super) fn auto_speed(
    xyz: &[f32],
    missing: &[bool],
    frames: &[ModelFrames],
    n: usize,
    rate_hz: f64,
) -> Option<f64> {
    let mut speeds = Vec::new();
    let mut start = 0;
    for take in frames {
        for f in start + 1..start + take.frames() {
            for m in 0..n {
                if !missing[(f - 1) * n + m] && !missing[f * n + m] {
                    let d2: f32 = (0..3)
                        .map(|k| {
                            (xyz[(f * n + m) * 3 + k] - xyz[((f - 1) * n + m) * 3 + k]).powi(2)
                        })
                        .sum();
                    speeds.push(f64::from(d2.sqrt()) * rate_hz);
                }
            }
        }
        start += take.frames();
    }
    if speeds.is_empty() {
        return None;
    }
    Some((quantile(&mut speeds, 0.999) * AUTO_SPEED_FACTOR).max(MIN_AUTO_SPEED_MM_S))
}

/// Samples flagged missing after preparation but present in the input, per marker.
pub(super) fn glitches_per_marker(
    frames: &[ModelFrames],
    prepared_missing: &[bool],
    n: usize,
) -> Vec<usize> {
    let input = frames.iter().flat_map(|f| f.missing.iter().copied());
    let mut counts = vec![0; n];
    for (i, (before, after)) in input.zip(prepared_missing).enumerate() {
        if !before && *after {
            counts[i % n] += 1;
        }
    }
    counts
}
