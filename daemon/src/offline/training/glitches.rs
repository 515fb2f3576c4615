//! What counts as a glitch: a marker faster than a speed limit (set from the data unless
//! given), or outside its learned plausible ball.

use ica_core::model::MarkerBounds;
use ica_core::robust::{quantile, quantile_f32};

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
    // Each marker's present positions, axis by axis, gathered in one pass over the frames:
    // read marker by marker, the frame-major layout would miss the cache at every sample.
    // Sized for every frame at once: grown push by push, they were copied and faulted in again
    // at every doubling.
    let frames = xyz.len() / (3 * n.max(1));
    let mut axes: Vec<[Vec<f32>; 3]> = (0..n)
        .map(|_| std::array::from_fn(|_| Vec::with_capacity(frames)))
        .collect();
    for (frame, gone) in xyz
        .chunks_exact(3 * n.max(1))
        .zip(missing.chunks_exact(n.max(1)))
    {
        for ((p, &gone), axes) in frame.chunks_exact(3).zip(gone).zip(&mut axes) {
            if !gone {
                for (axis, &v) in axes.iter_mut().zip(p) {
                    axis.push(v);
                }
            }
        }
    }
    // Markers at once on the current rayon pool; each marker's numbers are its own.
    let (centre, radius_mm) = axes
        .into_par_iter()
        .map(|axes| {
            // Selected in f32, on a copy (selection reorders; the axes stay paired): the same
            // values as in f64, since widening keeps the order.
            let mut c = [0.0f64; 3];
            let mut scratch = Vec::with_capacity(axes[0].len());
            for (slot, axis) in c.iter_mut().zip(&axes) {
                scratch.clear();
                scratch.extend_from_slice(axis);
                *slot = f64::from(quantile_f32(&mut scratch, 0.5));
            }
            let [x, y, z] = &axes;
            // Squared distances: the square root of their percentile is the percentile of
            // the distances.
            let mut d2: Vec<f64> = (0..x.len())
                .map(|i| {
                    [x[i], y[i], z[i]]
                        .iter()
                        .zip(&c)
                        .map(|(&v, &c)| (f64::from(v) - c).powi(2))
                        .sum::<f64>()
                })
                .collect();
            let r = quantile(&mut d2, 0.99).sqrt() * BOUNDS_FACTOR;
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
    // Squared steps in f32: the speed is a growing function of the step, so the percentile
    // step gives the percentile speed, without a square root or a widening per sample.
    let total: usize = frames.iter().map(ModelFrames::frames).sum();
    let mut steps = Vec::with_capacity(total * n);
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
                    steps.push(d2);
                }
            }
        }
        start += take.frames();
    }
    if steps.is_empty() {
        return None;
    }
    let step = quantile_f32(&mut steps, 0.999).sqrt();
    Some((f64::from(step) * rate_hz * AUTO_SPEED_FACTOR).max(MIN_AUTO_SPEED_MM_S))
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

#[cfg(test)]
mod tests;
