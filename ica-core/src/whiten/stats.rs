//! One-pass-per-statistic scans of the training data: which frames count, the mean, the
//! covariance (whose diagonal gives the per-channel variances) and the whitened projection. All sums are in f64.

use nalgebra::DMatrix;

use super::syrk::{accumulate_upper, mirror_upper};
use crate::linalg::{cols, cols_mut, product};

use crate::input::{FitData, FitError};

/// A frame is used when its missing channels are exactly those missing everywhere.
pub(crate) fn frame_is_used(missing_everywhere: &[bool], missing: Option<&[bool]>) -> bool {
    match missing {
        None => !missing_everywhere.contains(&true),
        Some(flags) => flags == missing_everywhere,
    }
}

/// Frames gathered per gemm call: large enough to amortise packing, small enough to stay in cache.
const CHUNK_FRAMES: usize = 256;

/// Which frames and channels take part.
#[derive(Debug)]
pub(crate) struct Selection {
    /// Frames with no missing sample (on channels that are not missing everywhere).
    pub used_frames: Vec<usize>,
    /// Channels missing in every frame.
    pub always_missing: Vec<bool>,
    /// Per-channel sums over the used frames, when the selection pass could form them.
    sums: Option<Vec<f64>>,
}

/// Checks every present sample is finite and picks the complete frames.
pub(crate) fn select<T: Copy + Into<f64>>(data: &FitData<'_, T>) -> Result<Selection, FitError> {
    let (frames, channels) = (data.frames(), data.channels());
    if !data.has_mask() {
        // Without a mask every frame is used, and the column sums are finite exactly when every
        // sample is (f32 or f64 values cannot overflow an f64 sum of any realistic length):
        // one branch-free, vectorised pass checks the data and forms the mean's sums. Only bad
        // data takes the scan below, which names the first bad sample.
        let mut sums = vec![0.0f64; channels];
        for f in 0..frames {
            for (s, &v) in sums.iter_mut().zip(data.frame(f)) {
                *s += v.into();
            }
        }
        if sums.iter().all(|s| s.is_finite()) {
            return Ok(Selection {
                used_frames: (0..frames).collect(),
                always_missing: vec![false; channels],
                sums: Some(sums),
            });
        }
    }
    let mut missing_count = vec![0usize; channels];
    for f in 0..frames {
        let values = data.frame(f);
        let flags = data.frame_missing(f);
        for (c, &v) in values.iter().enumerate() {
            if flags.is_some_and(|m| m[c]) {
                missing_count[c] += 1;
                continue;
            }
            let value: f64 = v.into();
            if !value.is_finite() {
                return Err(FitError::NonFinite {
                    frame: f,
                    channel: c,
                    value,
                });
            }
        }
    }
    let always_missing: Vec<bool> = missing_count
        .iter()
        .map(|&n| frames > 0 && n == frames)
        .collect();
    let used_frames = (0..frames)
        .filter(|&f| match data.frame_missing(f) {
            None => true,
            Some(flags) => flags
                .iter()
                .zip(&always_missing)
                .all(|(&miss, &dead)| !miss || dead),
        })
        .collect();
    Ok(Selection {
        used_frames,
        always_missing,
        sums: None,
    })
}

/// Per-channel mean over the used frames (0 for channels missing everywhere).
pub(crate) fn mean<T: Copy + Into<f64>>(data: &FitData<'_, T>, sel: &Selection) -> Vec<f64> {
    let n = sel.used_frames.len().max(1) as f64;
    if let Some(sums) = &sel.sums {
        return sums.iter().map(|s| s / n).collect();
    }
    let mut sum = vec![0.0f64; data.channels()];
    for &f in &sel.used_frames {
        for ((s, &v), &dead) in sum.iter_mut().zip(data.frame(f)).zip(&sel.always_missing) {
            if !dead {
                *s += v.into();
            }
        }
    }
    sum.iter_mut().for_each(|s| *s /= n);
    sum
}

/// Calls `each(start, chunk, frames)` with the used frames, `CHUNK_FRAMES` at a time, centred
/// and restricted to `live` channels: `chunk` is `live.len() x frames` column-major (one frame
/// per column), ready for a matrix product.
fn for_each_chunk<T: Copy + Into<f64>>(
    data: &FitData<'_, T>,
    used: &[usize],
    live: &[usize],
    mean: &[f64],
    mut each: impl FnMut(usize, &[f64], usize),
) {
    let nl = live.len();
    // With every channel live (the usual case) a frame is converted as one contiguous run,
    // which vectorises; the indexed gather below does not.
    let all_live = nl == data.channels();
    let mut buf = vec![0.0f64; nl * CHUNK_FRAMES];
    for (k, frames) in used.chunks(CHUNK_FRAMES).enumerate() {
        for (col, &f) in buf.chunks_exact_mut(nl).zip(frames) {
            let values = data.frame(f);
            if all_live {
                for ((dst, &v), &mu) in col.iter_mut().zip(values).zip(mean) {
                    *dst = v.into() - mu;
                }
            } else {
                for (dst, &c) in col.iter_mut().zip(live) {
                    *dst = values[c].into() - mean[c];
                }
            }
        }
        let raw = &buf[..nl * frames.len()];
        each(k * CHUNK_FRAMES, raw, frames.len());
    }
}

/// Unbiased covariance of the live channels over the used frames, `live x live`.
pub(crate) fn covariance<T: Copy + Into<f64>>(
    data: &FitData<'_, T>,
    used: &[usize],
    live: &[usize],
    mean: &[f64],
) -> DMatrix<f64> {
    let nl = live.len();
    let mut cov = DMatrix::<f64>::zeros(nl, nl);
    for_each_chunk(data, used, live, mean, |_, raw, _| {
        accumulate_upper(&mut cov, raw);
    });
    mirror_upper(&mut cov);
    let dof = (used.len().max(2) - 1) as f64;
    cov /= dof;
    cov
}

/// Projects the used frames onto `rows` (`m x live`): returns `m x used` with one frame per column.
pub(crate) fn project<T: Copy + Into<f64>>(
    data: &FitData<'_, T>,
    used: &[usize],
    live: &[usize],
    mean: &[f64],
    rows: &DMatrix<f64>,
) -> DMatrix<f64> {
    let mut z = DMatrix::<f64>::zeros(rows.nrows(), used.len());
    let (m, nl) = rows.shape();
    for_each_chunk(data, used, live, mean, |start, raw, n| {
        product(
            cols_mut(&mut z.as_mut_slice()[start * m..], m, n),
            cols(rows.as_slice(), m, nl),
            cols(raw, nl, n),
        );
    });
    z
}
