//! The capture as the head search reads it: frames in one marker order ([`MarkerFrames`]), a
//! bounded sample of them with neighbours and glitches masked ([`Sample`]), and the robust
//! statistics both the search and the assessment use.

use crate::robust::{mad, median, quantile_f32};

/// Frames of a capture in one marker order, take by take (differences never cross a take
/// boundary). The takes are borrowed where they lie, so a caller holding them apart need not
/// join them.
#[derive(Debug, Clone, Copy)]
pub struct MarkerFrames<'a> {
    /// Each take's frames.
    pub takes: &'a [TakeFrames<'a>],
    /// Markers per frame.
    pub markers: usize,
}

/// One take's frames (or one stretch of a take) in [`MarkerFrames`]' marker order.
#[derive(Debug, Clone, Copy)]
pub struct TakeFrames<'a> {
    /// Positions, frames x markers x 3 (mm).
    pub xyz: &'a [f32],
    /// Missing flags, frames x markers.
    pub missing: &'a [bool],
}

/// Sampled frames, each with its two neighbours, glitches masked.
pub(crate) struct Sample {
    /// 3 frames per sample (before, at, after), markers x 3 each.
    xyz: Vec<f32>,
    /// Present (not missing, not a glitch), 3 frames per sample, markers each.
    present: Vec<bool>,
    markers: usize,
    pub(crate) glitches: usize,
    /// The same positions marker by marker, axis by axis (NaN where not present): what the
    /// loops over one marker's or one pair's frames read, contiguous so they vectorise.
    columns: Vec<f32>,
}

/// Glitch speed: this multiple of the 99.9th percentile speed, at least [`MIN_GLITCH_MM_S`]
/// (per frame here: the sample has no rate, so speeds are mm per frame).
const GLITCH_FACTOR: f64 = 4.0;
/// Smallest glitch step, mm per frame.
const MIN_GLITCH_STEP_MM: f64 = 4.0;

impl Sample {
    pub(crate) fn draw(frames: &MarkerFrames<'_>, max_frames: usize) -> Sample {
        let n = frames.markers;
        let lengths: Vec<usize> = (frames.takes.iter())
            .map(|t| t.missing.len() / n.max(1))
            .collect();
        let inner: usize = lengths.iter().map(|l| l.saturating_sub(2)).sum();
        let stride = (inner / max_frames.max(1)).max(1);
        let sampled = inner / stride;
        let mut xyz = Vec::with_capacity(sampled * 3 * n * 3);
        let mut present = Vec::with_capacity(sampled * 3 * n);
        let mut k = 0usize;
        for (take, &len) in frames.takes.iter().zip(&lengths) {
            for f in 1..len.saturating_sub(1) {
                k += 1;
                if k % stride != 0 {
                    continue;
                }
                xyz.extend_from_slice(&take.xyz[(f - 1) * n * 3..(f + 2) * n * 3]);
                present.extend(take.missing[(f - 1) * n..(f + 2) * n].iter().map(|m| !m));
            }
        }
        let mut sample = Sample {
            xyz,
            present,
            markers: n,
            glitches: 0,
            columns: Vec::new(),
        };
        sample.mask_glitches();
        sample.columns = sample.transposed();
        sample
    }

    /// [`Sample::columns`] from the frame-major storage, written column by column, columns at
    /// once on the current rayon pool.
    fn transposed(&self) -> Vec<f32> {
        use rayon::prelude::*;
        let (n, t) = (self.markers, self.present.len() / self.markers.max(1));
        let mut columns = vec![0.0; n * 3 * t];
        let columns_of = columns.par_chunks_exact_mut(t.max(1)).enumerate();
        columns_of.for_each(|(c, column)| {
            let (m, axis) = (c / 3, c % 3);
            for (f, v) in column.iter_mut().enumerate() {
                let i = f * n + m;
                *v = if self.present[i] {
                    self.xyz[i * 3 + axis]
                } else {
                    f32::NAN
                };
            }
        });
        columns
    }

    /// Marker `m`'s coordinate `axis` over the stored frames (3 per sample), NaN where absent.
    pub(crate) fn column(&self, m: usize, axis: usize) -> &[f32] {
        let t = 3 * self.frames();
        &self.columns[(m * 3 + axis) * t..(m * 3 + axis + 1) * t]
    }

    /// Sampled frames (centres).
    pub(crate) fn frames(&self) -> usize {
        self.present.len() / (3 * self.markers.max(1))
    }

    /// A present sample's x y z.
    pub(crate) fn get(&self, frame: usize, marker: usize) -> Option<&[f32]> {
        let i = frame * self.markers + marker;
        self.present[i].then(|| &self.xyz[i * 3..i * 3 + 3])
    }

    /// Marks samples whose step to a neighbour is a glitch (see [`GLITCH_FACTOR`]).
    fn mask_glitches(&mut self) {
        // Both steps of every triple and marker (NaN where a sample is missing), measured once,
        // in f32 (the limit is a multiple of a percentile: its last digits decide nothing).
        let n = self.markers;
        let frame = 3 * n;
        let mut both = Vec::with_capacity(2 * self.present.len() / 3);
        for (xyz, present) in self
            .xyz
            .chunks_exact(3 * frame.max(1))
            .zip(self.present.chunks_exact(frame.max(1)))
        {
            let (b, rest) = xyz.split_at(frame);
            let (a, after) = rest.split_at(frame);
            for m in 0..n {
                let step = |p: &[f32], q: &[f32], ok: bool| {
                    let d = (p[3 * m] - q[3 * m]).powi(2)
                        + (p[3 * m + 1] - q[3 * m + 1]).powi(2)
                        + (p[3 * m + 2] - q[3 * m + 2]).powi(2);
                    if ok {
                        d.sqrt()
                    } else {
                        f32::NAN
                    }
                };
                let (pb, pa, pn) = (present[m], present[n + m], present[2 * n + m]);
                both.push(step(b, a, pb && pa));
                both.push(step(a, after, pa && pn));
            }
        }
        let mut steps: Vec<f32> = both.iter().copied().filter(|v| !v.is_nan()).collect();
        let limit =
            (GLITCH_FACTOR * f64::from(quantile_f32(&mut steps, 0.999))).max(MIN_GLITCH_STEP_MM);
        for (s, pair) in both.chunks_exact(2).enumerate() {
            // NaN (missing) is never above the limit.
            if pair.iter().any(|&v| f64::from(v) > limit) {
                let (triple, m) = (s / n.max(1), s % n.max(1));
                for g in 3 * triple..3 * triple + 3 {
                    let i = g * n + m;
                    self.glitches += usize::from(self.present[i]);
                    self.present[i] = false;
                }
            }
        }
    }

    pub(crate) fn present_share(&self, m: usize) -> f64 {
        let centres = self.column(m, 0).iter().skip(1).step_by(3);
        centres.filter(|v| !v.is_nan()).count() as f64 / self.frames().max(1) as f64
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
        let column = self.column(m, axis);
        d2.extend(column.chunks_exact(3).filter_map(|t| {
            let v = f64::from(t[0]) - 2.0 * f64::from(t[1]) + f64::from(t[2]);
            v.is_finite().then_some(v)
        }));
        (d2.len() >= 10).then(|| mad(d2) / 6f64.sqrt())
    }
}
