//! Timing warps: each take speaks its sentence at its own, smoothly varying pace.
//!
//! A warp maps frame index -> canonical time (seconds into the sentence). It is strictly
//! increasing, starts at 0 and ends at the sentence's canonical duration, so aligning two takes
//! of one sentence needs a non-linear alignment (DTW), not a single scale.

use std::f64::consts::PI;

use rand::Rng;
use serde::{Deserialize, Serialize};

/// Range of the overall duration scale of a take (real / canonical).
pub const SCALE_RANGE: (f64, f64) = (0.82, 1.18);
/// Range of the amplitude of the first harmonic of the log local pace (so the pace always
/// varies by at least ~±10% within a take).
const LOCAL_LOG_RATE: (f64, f64) = (0.1, 0.2);

/// Canonical time of each frame of a take.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Warp {
    /// Canonical seconds, one per frame, strictly increasing.
    pub canonical_s: Vec<f64>,
}

impl Warp {
    /// A uniform warp: `scale` real seconds per canonical second (1.0 = canonical timing).
    pub fn uniform(canonical_duration_s: f64, rate_hz: f64, scale: f64) -> Warp {
        let n = frame_count(canonical_duration_s * scale, rate_hz);
        let step = canonical_duration_s / (n - 1) as f64;
        Warp {
            canonical_s: (0..n).map(|f| f as f64 * step).collect(),
        }
    }

    /// A random smooth monotonic warp: overall scale in [`SCALE_RANGE`], local pace modulated
    /// by a few low harmonics (about ±10-25%), endpoints pinned to 0 and the canonical duration.
    pub fn random(rng: &mut impl Rng, canonical_duration_s: f64, rate_hz: f64) -> Warp {
        Warp::random_paced(rng, canonical_duration_s, rate_hz, 1.0)
    }

    /// [`Warp::random`] spoken `pace` times as fast (1.2: 20 % faster, a take 1/1.2 as long).
    pub fn random_paced(
        rng: &mut impl Rng,
        canonical_duration_s: f64,
        rate_hz: f64,
        pace: f64,
    ) -> Warp {
        let scale = rng.random_range(SCALE_RANGE.0..SCALE_RANGE.1);
        let n = frame_count(canonical_duration_s * scale / pace, rate_hz);
        let harmonics: Vec<(f64, f64, f64)> = (1..=3)
            .map(|k| {
                let k = f64::from(k);
                let mag = if k == 1.0 {
                    rng.random_range(LOCAL_LOG_RATE.0..LOCAL_LOG_RATE.1)
                } else {
                    rng.random_range(0.0..LOCAL_LOG_RATE.0) / k
                };
                let amp = if rng.random_bool(0.5) { mag } else { -mag };
                (k, amp, rng.random_range(0.0..2.0 * PI))
            })
            .collect();
        let density = |u: f64| {
            harmonics
                .iter()
                .map(|&(k, a, p)| a * (k * PI * u + p).sin())
                .sum::<f64>()
                .exp()
        };
        // Cumulative trapezoid integral of the pace density over the frame grid, 4 substeps.
        let sub = 4;
        let du = 1.0 / ((n - 1) * sub) as f64;
        let mut cum = Vec::with_capacity(n);
        let mut acc = 0.0;
        cum.push(0.0);
        for f in 1..n {
            for s in 0..sub {
                let u0 = ((f - 1) * sub + s) as f64 * du;
                acc += 0.5 * (density(u0) + density(u0 + du)) * du;
            }
            cum.push(acc);
        }
        let total = acc;
        Warp {
            canonical_s: cum
                .iter()
                .map(|c| canonical_duration_s * c / total)
                .collect(),
        }
    }

    /// Number of frames.
    pub fn n_frames(&self) -> usize {
        self.canonical_s.len()
    }

    /// Canonical duration covered (canonical time of the last frame).
    pub fn canonical_duration_s(&self) -> f64 {
        self.canonical_s.last().copied().unwrap_or(0.0)
    }

    /// Fractional frame index at which the take reaches canonical time `tau` (clamped to the
    /// take): the inverse warp, for un-warping a take onto canonical time.
    pub fn frame_at(&self, tau: f64) -> f64 {
        let c = &self.canonical_s;
        if c.len() < 2 || tau <= c[0] {
            return 0.0;
        }
        if tau >= c[c.len() - 1] {
            return (c.len() - 1) as f64;
        }
        let hi = c.partition_point(|&v| v <= tau);
        let lo = hi - 1;
        lo as f64 + (tau - c[lo]) / (c[hi] - c[lo])
    }
}

/// Frames needed to span `duration_s` at `rate_hz`, both ends included (at least 2).
fn frame_count(duration_s: f64, rate_hz: f64) -> usize {
    ((duration_s * rate_hz).round() as usize + 1).max(2)
}

#[cfg(test)]
mod tests;
