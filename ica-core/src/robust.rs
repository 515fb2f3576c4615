//! Robust statistics on scratch slices: median, quantiles, the MAD. The one quantile rule of
//! the workspace: the nearest rank, `round((n - 1)·q)`, found by selection.

/// Median (reorders `v`); 0 when empty.
pub fn median(v: &mut [f64]) -> f64 {
    quantile(v, 0.5)
}

/// The nearest rank of the `q`-quantile among `n > 0` values.
fn rank(n: usize, q: f64) -> usize {
    ((n - 1) as f64 * q).round() as usize
}

/// `q`-quantile by selection (reorders `v`); 0 when empty.
pub fn quantile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    *v.select_nth_unstable_by(rank(v.len(), q), f64::total_cmp).1
}

/// [`quantile`] of `f32` values (reorders `v`): the same rank, so the same value as
/// [`quantile`] of the values widened to `f64`, selected in half the memory.
pub fn quantile_f32(v: &mut [f32], q: f64) -> f32 {
    if v.is_empty() {
        return 0.0;
    }
    *v.select_nth_unstable_by(rank(v.len(), q), f32::total_cmp).1
}

/// `1.4826 · MAD`, a robust standard deviation (reorders `v`).
pub fn mad(v: &mut [f64]) -> f64 {
    let m = median(v);
    for x in v.iter_mut() {
        *x = (*x - m).abs();
    }
    1.4826 * median(v)
}
