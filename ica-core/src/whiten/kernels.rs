//! The per-frame loops of the moment scan, written so that they vectorise: centring a frame
//! and checking that a chunk is finite run once per sample of hours of data.

/// `dst = x - reference` on the channels not in `dead`, 0 on the others (whose values may be
/// NaN and are never read); `dead = None` when no channel is missing everywhere.
#[inline]
pub(super) fn centre_into<T: Copy + Into<f64>>(
    dst: &mut [f64],
    x: &[T],
    dead: Option<&[bool]>,
    reference: &[f64],
) {
    match dead {
        // The common case as one branch-free loop, which vectorises.
        None => {
            for ((d, &v), &mu) in dst.iter_mut().zip(x).zip(reference) {
                *d = v.into() - mu;
            }
        }
        Some(dead) => {
            for (c, (d, &v)) in dst.iter_mut().zip(x).enumerate() {
                *d = if dead[c] {
                    0.0
                } else {
                    v.into() - reference[c]
                };
            }
        }
    }
}

/// Whether every value is finite: `0 * v` is 0 for finite `v` and NaN otherwise, summed in
/// eight lanes so the loop vectorises (a short-circuiting scan does not).
pub(super) fn all_finite<T: Copy + Into<f64>>(values: &[T]) -> bool {
    let mut lanes = [0.0f64; 8];
    let mut chunks = values.chunks_exact(8);
    for chunk in &mut chunks {
        for (l, &v) in lanes.iter_mut().zip(chunk) {
            *l += v.into() * 0.0;
        }
    }
    let rest: f64 = chunks.remainder().iter().map(|&v| v.into() * 0.0).sum();
    (lanes.iter().sum::<f64>() + rest) == 0.0
}
