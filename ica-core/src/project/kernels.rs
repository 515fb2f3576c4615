//! The f32 inner loops of the frame path, written so the compiler vectorises them without
//! `unsafe` or target-specific code: fixed-width lane arrays for reductions (a plain `sum`
//! is a serial chain, since float addition is not associative) and element-wise loops over
//! zipped slices (no bounds checks) for updates.

/// Lanes per reduction: four SSE or two AVX registers, enough independent adds to hide
/// latency.
const LANES: usize = 16;

/// `Σ a_i b_i` over the shorter of the two slices.
#[inline]
pub(crate) fn dot(a: &[f32], b: &[f32]) -> f32 {
    let ca = a.chunks_exact(LANES);
    let cb = b.chunks_exact(LANES);
    let mut tail = 0.0_f32;
    for (x, y) in ca.remainder().iter().zip(cb.remainder()) {
        tail += x * y;
    }
    let mut acc = [0.0_f32; LANES];
    for (x, y) in ca.zip(cb) {
        for i in 0..LANES {
            acc[i] += x[i] * y[i];
        }
    }
    reduce(acc) + tail
}

/// Panel widths [`panel_gemv`] is instantiated for.
pub(crate) const PANEL_WIDTHS: [usize; 8] = [4, 8, 12, 16, 20, 24, 28, 32];

/// `u = W (x − mean)` for `wt` = `Wᵀ` as n rows of `K` (zero padded from `u.len()` to `K`
/// columns): `acc += (x_j − mean_j) · wt[j]`. With `K` known at compile time the accumulator
/// lives in registers and each row is a handful of vector multiply-adds.
#[inline]
pub(crate) fn panel_gemv<const K: usize>(wt: &[f32], x: &[f32], mean: &[f32], u: &mut [f32]) {
    if K <= 8 {
        return panel_gemv_pairs::<K>(wt, x, mean, u);
    }
    let mut acc = [0.0_f32; K];
    for ((row, &xj), &mj) in wt.chunks_exact(K).zip(x).zip(mean) {
        let cj = xj - mj;
        for i in 0..K {
            acc[i] += cj * row[i];
        }
    }
    u.copy_from_slice(&acc[..u.len()]);
}

/// [`panel_gemv`] for narrow panels: with one or two registers of accumulator every row
/// would wait on the previous row's add, so even and odd rows accumulate separately
/// (measured 458 -> 382 ns per frame at m = 6; wider panels have enough independent lanes
/// already and slow down from the register pressure).
fn panel_gemv_pairs<const K: usize>(wt: &[f32], x: &[f32], mean: &[f32], u: &mut [f32]) {
    let (mut even, mut odd) = ([0.0_f32; K], [0.0_f32; K]);
    let rows = wt.chunks_exact(2 * K);
    let last = rows.remainder();
    let (xs, ms) = (x.chunks_exact(2), mean.chunks_exact(2));
    let (x_last, m_last) = (xs.remainder(), ms.remainder());
    for ((pair, xp), mp) in rows.zip(xs).zip(ms) {
        let (c0, c1) = (xp[0] - mp[0], xp[1] - mp[1]);
        let (r0, r1) = pair.split_at(K);
        for i in 0..K {
            even[i] += c0 * r0[i];
            odd[i] += c1 * r1[i];
        }
    }
    if let (Some(&xj), Some(&mj)) = (x_last.first(), m_last.first()) {
        for i in 0..K {
            even[i] += (xj - mj) * last[i];
        }
    }
    for ((o, e), d) in u.iter_mut().zip(&even).zip(&odd) {
        *o = e + d;
    }
}

fn reduce(acc: [f32; LANES]) -> f32 {
    let mut half = [0.0_f32; LANES / 2];
    for i in 0..LANES / 2 {
        half[i] = acc[i] + acc[i + LANES / 2];
    }
    half.iter().sum()
}

/// `y += a x`.
#[inline]
pub(crate) fn axpy(a: f32, x: &[f32], y: &mut [f32]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

/// `y += a0 x0 + a1 x1 + a2 x2 + a3 x3`: one pass over `y` for four columns, so `y` is
/// loaded and stored a quarter as often as with four [`axpy`] calls.
#[inline]
pub(crate) fn axpy4(a: [f32; 4], x: [&[f32]; 4], y: &mut [f32]) {
    let n = y.len();
    let (x0, x1, x2, x3) = (&x[0][..n], &x[1][..n], &x[2][..n], &x[3][..n]);
    for j in 0..n {
        y[j] += a[0] * x0[j] + a[1] * x1[j] + a[2] * x2[j] + a[3] * x3[j];
    }
}

/// `y = base + a0 x0 + a1 x1 + a2 x2 + a3 x3`: [`axpy4`] that starts from `base` instead of
/// reading `y`, so resynthesis needs no separate copy of the mean (one pass over `y` fewer).
#[inline]
pub(crate) fn axpy4_onto(base: &[f32], a: [f32; 4], x: [&[f32]; 4], y: &mut [f32]) {
    let n = y.len();
    let (b, x0, x1, x2, x3) = (&base[..n], &x[0][..n], &x[1][..n], &x[2][..n], &x[3][..n]);
    for j in 0..n {
        // the sum first, as in axpy4 from a copy of `base`: bit-identical results
        y[j] = b[j] + (a[0] * x0[j] + a[1] * x1[j] + a[2] * x2[j] + a[3] * x3[j]);
    }
}

/// `out = a - b`.
#[inline]
pub(crate) fn sub_into(a: &[f32], b: &[f32], out: &mut [f32]) {
    for ((o, ai), bi) in out.iter_mut().zip(a).zip(b) {
        *o = ai - bi;
    }
}

#[cfg(test)]
mod tests;
