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
    let mut axes: Vec<[Vec<f32>; 3]> = (0..n).map(|_| Default::default()).collect();
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
mod tests {
    use super::*;

    /// Frames of `n` markers wandering from place to place, some missing, one far glitch.
    fn frames(count: usize, n: usize) -> (Vec<f32>, Vec<bool>) {
        let (mut xyz, mut missing) = (Vec::new(), Vec::new());
        let mut state = 12345u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) as f64 / (1u64 << 31) as f64) as f32 - 0.5
        };
        for f in 0..count {
            for m in 0..n {
                let base = [m as f32 * 10.0, (f % 50) as f32 * 0.3, -(m as f32)];
                xyz.extend(base.map(|b| b + 5.0 * next()));
                missing.push((f * 7 + m * 3) % 11 == 0);
            }
        }
        xyz[3 * n * (count / 2)] += 400.0;
        (xyz, missing)
    }

    /// The definitions written plainly: medians of each axis, percentile of the distances,
    /// percentile of the speeds, all in f64.
    fn plain_bounds(xyz: &[f32], missing: &[bool], n: usize) -> MarkerBounds {
        let frames = missing.len() / n;
        let (mut centre, mut radius_mm) = (Vec::new(), Vec::new());
        for m in 0..n {
            let present: Vec<usize> = (0..frames).filter(|&f| !missing[f * n + m]).collect();
            let at = |f: usize, a: usize| f64::from(xyz[(f * n + m) * 3 + a]);
            let mut c = [0.0; 3];
            for (a, slot) in c.iter_mut().enumerate() {
                let mut v: Vec<f64> = present.iter().map(|&f| at(f, a)).collect();
                *slot = quantile(&mut v, 0.5);
            }
            let mut d: Vec<f64> = present
                .iter()
                .map(|&f| {
                    (0..3)
                        .map(|a| (at(f, a) - c[a]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .collect();
            centre.push(c);
            radius_mm.push((quantile(&mut d, 0.99) * BOUNDS_FACTOR).max(MIN_BOUNDS_MM));
        }
        MarkerBounds { centre, radius_mm }
    }

    #[test]
    fn bounds_and_speed_are_the_plain_definitions_value_for_value() {
        let n = 7;
        let (xyz, missing) = frames(900, n);
        let bounds = marker_bounds(&xyz, &missing, n);
        assert_eq!(bounds, plain_bounds(&xyz, &missing, n));
        let past_floor = bounds
            .radius_mm
            .iter()
            .filter(|&&r| r > MIN_BOUNDS_MM)
            .count();
        assert!(
            past_floor > n / 2,
            "the test must reach past the floor: {bounds:?}"
        );
        let takes: Vec<ModelFrames> = [400, 500]
            .iter()
            .scan(0, |start, &len| {
                let r = *start..*start + len;
                *start += len;
                Some(ModelFrames {
                    xyz: xyz[r.start * n * 3..r.end * n * 3].to_vec(),
                    missing: missing[r.start * n..r.end * n].to_vec(),
                    markers: n,
                })
            })
            .collect();
        let mut speeds = Vec::new();
        for take in &takes {
            for f in 1..take.frames() {
                let ((a, ma), (b, mb)) = (take.frame(f - 1), take.frame(f));
                for m in (0..n).filter(|&m| !ma[m] && !mb[m]) {
                    let d2: f32 = (0..3).map(|k| (b[m * 3 + k] - a[m * 3 + k]).powi(2)).sum();
                    speeds.push(f64::from(d2.sqrt()) * 120.0);
                }
            }
        }
        let plain = (quantile(&mut speeds, 0.999) * AUTO_SPEED_FACTOR).max(MIN_AUTO_SPEED_MM_S);
        let got = auto_speed(&xyz, &missing, &takes, n, 120.0).expect("speeds");
        assert_eq!(got.to_bits(), plain.to_bits(), "{got} vs {plain}");
        assert!(
            got > MIN_AUTO_SPEED_MM_S,
            "the test must reach past the floor: {got}"
        );
    }
}
