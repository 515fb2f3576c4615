//! Dynamic time warping of two multi-dimensional series, with an optional Sakoe-Chiba band.
//!
//! The local cost is the squared Euclidean distance between frames; the step pattern is the
//! symmetric one (match, insertion, deletion, each at the local cost). The path runs from
//! `(0, 0)` to `(n - 1, m - 1)`.
//!
//! Memory: without a band the table is `n x m` direction bytes; with a band of radius `r` only
//! `n x (2r + s + 1)` bytes are kept, where `s` absorbs the slope of unequal lengths, and the
//! accumulated cost needs two rows. Time is proportional to the cells inside the band.
//!
//! ```
//! use ica_core::dtw::align;
//! let a = [0.0, 1.0, 2.0, 3.0];
//! let b = [0.0, 0.0, 1.0, 2.0, 3.0];
//! let al = align(&a, &b, 1, None).unwrap();
//! assert_eq!(al.cost, 0.0);
//! assert_eq!(al.path.first(), Some(&(0, 0)));
//! assert_eq!(al.path.last(), Some(&(3, 4)));
//! ```

/// Why two series could not be aligned.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum DtwError {
    /// One of the series has no frames.
    #[error("cannot align an empty series")]
    Empty,
    /// The dimension is zero or does not divide a series' length.
    #[error("series of {len} values is not a whole number of {dim}-dimensional frames")]
    BadShape {
        /// Values in the series.
        len: usize,
        /// Frame dimension.
        dim: usize,
    },
    /// A value is NaN or infinite.
    #[error("series value {index} is not finite")]
    NonFinite {
        /// Index of the first bad value.
        index: usize,
    },
}

/// An optimal alignment: matched frame pairs in order, and its total cost.
#[derive(Debug, Clone, PartialEq)]
pub struct Alignment {
    /// `(i, j)` pairs: frame `i` of the first series is matched with frame `j` of the second.
    pub path: Vec<(usize, usize)>,
    /// Sum of squared distances along the path.
    pub cost: f64,
}

const STEP_DIAG: u8 = 0;
const STEP_UP: u8 = 1; // from (i - 1, j)
const STEP_LEFT: u8 = 2; // from (i, j - 1)

/// Column window `[lo, hi]` of each row.
struct Band {
    n: usize,
    m: usize,
    radius: Option<usize>,
}

impl Band {
    fn window(&self, i: usize) -> (usize, usize) {
        let Some(r) = self.radius else {
            return (0, self.m - 1);
        };
        let centre = if self.n == 1 {
            0.0
        } else {
            i as f64 * (self.m - 1) as f64 / (self.n - 1) as f64
        };
        // Consecutive windows must overlap for every cell of the path to stay reachable: a
        // radius below the slope would leave gaps, so widen it to the slope.
        let slope = self.m.div_ceil(self.n).max(self.n.div_ceil(self.m));
        let r = r.max(slope);
        let lo = (centre.floor() as usize).saturating_sub(r);
        let hi = (centre.ceil() as usize + r).min(self.m - 1);
        (lo, hi)
    }

    fn width(&self) -> usize {
        (0..self.n)
            .map(|i| {
                let (lo, hi) = self.window(i);
                hi - lo + 1
            })
            .max()
            .unwrap_or(0)
    }
}

fn check(series: &[f64], dim: usize) -> Result<usize, DtwError> {
    if dim == 0 || series.len() % dim != 0 {
        return Err(DtwError::BadShape {
            len: series.len(),
            dim,
        });
    }
    if series.is_empty() {
        return Err(DtwError::Empty);
    }
    if let Some(index) = series.iter().position(|v| !v.is_finite()) {
        return Err(DtwError::NonFinite { index });
    }
    Ok(series.len() / dim)
}

fn sq_dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

/// Aligns series `a` (frames x `dim`, row-major) with series `b`.
///
/// `band` is the Sakoe-Chiba radius in frames around the diagonal joining the two corners;
/// `None` searches the whole table. The radius is widened to the length ratio when that is larger,
/// so a path always exists.
///
/// # Errors
/// [`DtwError`] for an empty series, a length that is not a multiple of `dim`, or a non-finite
/// value.
pub fn align(a: &[f64], b: &[f64], dim: usize, band: Option<usize>) -> Result<Alignment, DtwError> {
    let n = check(a, dim)?;
    let m = check(b, dim)?;
    let band = Band { n, m, radius: band };
    let width = band.width();
    let mut steps = vec![STEP_DIAG; n * width];
    let mut prev = vec![f64::INFINITY; m];
    let mut cur = vec![f64::INFINITY; m];
    let mut prev_window = (0, 0);
    for i in 0..n {
        let (lo, hi) = band.window(i);
        let row_a = &a[i * dim..(i + 1) * dim];
        for j in lo..=hi {
            let local = sq_dist(row_a, &b[j * dim..(j + 1) * dim]);
            let (best, step) = if i == 0 && j == 0 {
                (0.0, STEP_DIAG)
            } else {
                let in_prev = |jj: usize| i > 0 && jj >= prev_window.0 && jj <= prev_window.1;
                let diag = if j > 0 && in_prev(j - 1) {
                    prev[j - 1]
                } else {
                    f64::INFINITY
                };
                let up = if in_prev(j) { prev[j] } else { f64::INFINITY };
                let left = if j > lo { cur[j - 1] } else { f64::INFINITY };
                // Ties prefer the diagonal, then up, so the path is deterministic.
                if diag <= up && diag <= left {
                    (diag, STEP_DIAG)
                } else if up <= left {
                    (up, STEP_UP)
                } else {
                    (left, STEP_LEFT)
                }
            };
            cur[j] = best + local;
            steps[i * width + (j - lo)] = step;
        }
        std::mem::swap(&mut prev, &mut cur);
        prev_window = (lo, hi);
    }
    let cost = prev[m - 1];
    let path = backtrack(&band, &steps, width);
    Ok(Alignment { path, cost })
}

fn backtrack(band: &Band, steps: &[u8], width: usize) -> Vec<(usize, usize)> {
    let (mut i, mut j) = (band.n - 1, band.m - 1);
    let mut path = Vec::with_capacity(band.n + band.m);
    loop {
        path.push((i, j));
        if i == 0 && j == 0 {
            break;
        }
        let (lo, _) = band.window(i);
        match steps[i * width + (j - lo)] {
            STEP_UP => i -= 1,
            STEP_LEFT => j -= 1,
            _ => {
                i -= 1;
                j -= 1;
            }
        }
    }
    path.reverse();
    path
}

/// For each frame of `a`, the mean index of `b` it is matched with: a warp map from `a`'s
/// timeline into `b`'s, handy for resampling `b` onto `a`.
pub fn warp_map(path: &[(usize, usize)], n: usize) -> Vec<f64> {
    let mut sum = vec![0.0; n];
    let mut count = vec![0usize; n];
    for &(i, j) in path {
        if i < n {
            sum[i] += j as f64;
            count[i] += 1;
        }
    }
    sum.iter()
        .zip(&count)
        .map(|(s, &c)| if c == 0 { f64::NAN } else { s / c as f64 })
        .collect()
}

/// Each `dim`-wide column of a frames x dim series minus its mean over the frames: an offset
/// constant over a take (an emotion level) shifts every DTW cell of a pair equally at best and
/// biases the path at worst, so alignment looks at the motion around the level.
pub fn demeaned(series: &[f64], dim: usize) -> Vec<f64> {
    let frames = (series.len() / dim.max(1)).max(1) as f64;
    let mut mean = vec![0.0; dim];
    for row in series.chunks_exact(dim) {
        for (acc, v) in mean.iter_mut().zip(row) {
            *acc += v / frames;
        }
    }
    series
        .iter()
        .enumerate()
        .map(|(i, v)| v - mean[i % dim])
        .collect()
}

/// For each frame of `target`, the fractional frame of `source` it matches: DTW of the two
/// demeaned series (frames x `dim`), Sakoe-Chiba `band`, averaged per target frame.
///
/// # Errors
/// As [`align`].
pub fn warp_onto(
    target: &[f64],
    source: &[f64],
    dim: usize,
    band: Option<usize>,
) -> Result<Vec<f64>, DtwError> {
    let alignment = align(&demeaned(target, dim), &demeaned(source, dim), dim, band)?;
    Ok(warp_map(&alignment.path, target.len() / dim.max(1)))
}

/// `values` read at fractional frames `at` by linear interpolation (clamped to the ends).
pub fn resample_at(values: &[f64], at: &[f64]) -> Vec<f64> {
    let last = values.len().saturating_sub(1);
    at.iter()
        .map(|&j| {
            let lo = (j.max(0.0).floor() as usize).min(last);
            let hi = (lo + 1).min(last);
            let t = (j - lo as f64).clamp(0.0, 1.0);
            values[lo] * (1.0 - t) + values[hi] * t
        })
        .collect()
}

#[cfg(test)]
mod tests;
