//! The capture as the head search reads it: frames in one marker order ([`MarkerFrames`]), a
//! bounded sample of them with neighbours and glitches masked ([`Sample`]), and the robust
//! statistics both the search and the assessment use.

use std::ops::Range;

use super::point;
use crate::robust::{mad, median, quantile};

/// Frames of a capture in one marker order: `xyz` frames x markers x 3 (mm), `missing` frames
/// x markers, and the frame range of each take (differences never cross a take boundary).
#[derive(Debug, Clone, Copy)]
pub struct MarkerFrames<'a> {
    /// Positions, frames x markers x 3 (mm).
    pub xyz: &'a [f32],
    /// Missing flags, frames x markers.
    pub missing: &'a [bool],
    /// Markers per frame.
    pub markers: usize,
    /// Frame range of each take.
    pub takes: &'a [Range<usize>],
}

/// Sampled frames, each with its two neighbours, glitches masked.
pub(crate) struct Sample {
    /// 3 frames per sample (before, at, after), markers x 3 each.
    xyz: Vec<f32>,
    /// Present (not missing, not a glitch), 3 frames per sample, markers each.
    present: Vec<bool>,
    markers: usize,
    pub(crate) glitches: usize,
}

/// Glitch speed: this multiple of the 99.9th percentile speed, at least [`MIN_GLITCH_MM_S`]
/// (per frame here: the sample has no rate, so speeds are mm per frame).
const GLITCH_FACTOR: f64 = 4.0;
/// Smallest glitch step, mm per frame.
const MIN_GLITCH_STEP_MM: f64 = 4.0;

impl Sample {
    pub(crate) fn draw(frames: &MarkerFrames<'_>, max_frames: usize) -> Sample {
        let n = frames.markers;
        let inner: usize = frames.takes.iter().map(|r| r.len().saturating_sub(2)).sum();
        let stride = (inner / max_frames.max(1)).max(1);
        let sampled = inner / stride;
        let mut xyz = Vec::with_capacity(sampled * 3 * n * 3);
        let mut present = Vec::with_capacity(sampled * 3 * n);
        let mut k = 0usize;
        for take in frames.takes {
            for f in take.start + 1..take.end.saturating_sub(1) {
                k += 1;
                if k % stride != 0 {
                    continue;
                }
                for g in f - 1..=f + 1 {
                    xyz.extend_from_slice(&frames.xyz[g * n * 3..(g + 1) * n * 3]);
                    present.extend(frames.missing[g * n..(g + 1) * n].iter().map(|m| !m));
                }
            }
        }
        let mut sample = Sample {
            xyz,
            present,
            markers: n,
            glitches: 0,
        };
        sample.mask_glitches();
        sample
    }

    /// Sampled frames (centres).
    pub(crate) fn frames(&self) -> usize {
        self.present.len() / (3 * self.markers.max(1))
    }

    /// Storage indices of sample `s`'s three frames.
    pub(crate) fn triple(&self, s: usize) -> [usize; 3] {
        [3 * s, 3 * s + 1, 3 * s + 2]
    }

    /// A present sample's x y z.
    pub(crate) fn get(&self, frame: usize, marker: usize) -> Option<&[f32]> {
        let i = frame * self.markers + marker;
        self.present[i].then(|| &self.xyz[i * 3..i * 3 + 3])
    }

    fn step(&self, a: usize, b: usize, m: usize) -> Option<f64> {
        Some((point(self.get(a, m)?, 0) - point(self.get(b, m)?, 0)).norm())
    }

    /// Marks samples whose step to a neighbour is a glitch (see [`GLITCH_FACTOR`]).
    fn mask_glitches(&mut self) {
        use rayon::prelude::*;
        // Both steps of every triple and marker (NaN where a sample is missing), measured once,
        // triples at once on the current rayon pool and collected in order.
        let markers = self.markers;
        let this = &*self;
        let both: Vec<[f64; 2]> = (0..self.frames())
            .into_par_iter()
            .flat_map_iter(|s| {
                let [b, a, n] = this.triple(s);
                (0..markers).map(move |m| {
                    let step = |x: usize, y: usize| this.step(x, y, m).unwrap_or(f64::NAN);
                    [step(b, a), step(a, n)]
                })
            })
            .collect();
        let mut steps: Vec<f64> = both
            .iter()
            .flatten()
            .copied()
            .filter(|v| !v.is_nan())
            .collect();
        let limit = (GLITCH_FACTOR * quantile(&mut steps, 0.999)).max(MIN_GLITCH_STEP_MM);
        for s in 0..self.frames() {
            let [b, a, n] = self.triple(s);
            for m in 0..self.markers {
                // NaN (missing) is never above the limit.
                if both[s * markers + m].iter().any(|&v| v > limit) {
                    for g in [b, a, n] {
                        let i = g * self.markers + m;
                        self.glitches += usize::from(self.present[i]);
                        self.present[i] = false;
                    }
                }
            }
        }
    }

    pub(crate) fn present_share(&self, m: usize) -> f64 {
        let at = (0..self.frames()).filter(|&s| self.get(3 * s + 1, m).is_some());
        at.count() as f64 / self.frames().max(1) as f64
    }

    /// Median over `markers` and axes of the robust spread of second differences / √6.
    pub(crate) fn noise_mm(&self, markers: &[usize]) -> f64 {
        use rayon::prelude::*;
        // Markers at once on the current rayon pool, collected in order.
        let mut per_axis: Vec<f64> = markers
            .par_iter()
            .flat_map_iter(|&m| {
                let mut d2 = Vec::new();
                (0..3)
                    .filter_map(|axis| self.axis_noise(m, axis, &mut d2))
                    .collect::<Vec<_>>()
            })
            .collect();
        median(&mut per_axis)
    }

    /// The robust spread of marker `m`'s second differences along `axis` / √6, from at least
    /// 10 of them (`d2` is scratch).
    fn axis_noise(&self, m: usize, axis: usize, d2: &mut Vec<f64>) -> Option<f64> {
        d2.clear();
        for s in 0..self.frames() {
            let [b, a, n] = self.triple(s);
            if let (Some(p), Some(q), Some(r)) = (self.get(b, m), self.get(a, m), self.get(n, m)) {
                d2.push(f64::from(p[axis]) - 2.0 * f64::from(q[axis]) + f64::from(r[axis]));
            }
        }
        (d2.len() >= 10).then(|| mad(d2) / 6f64.sqrt())
    }
}
