//! The frame kernels for AVX2 + FMA, with pulp's safe 8-lane type and the model's matrices in
//! the order the loops read them.
//!
//! **One matrix for both passes.** `W = M⁺`, so with the thin QR factorisation `M = Q R`
//! (`Q` n x m with orthonormal columns, `R` m x m upper triangular) the projection is
//! `u = R⁻¹ (Qᵀ c)` (`c = x − mean`) and the resynthesis `x' = mean + Q (R u')`: both large
//! products read the same `Q`, and the m x m ones are a few hundred multiply-adds. Storing `W`
//! and `M` instead took 52 KB at m = 20 and 109 markers, more than a core's 48 KB L1 cache:
//! a frame loop read both from L2 (0.75 µs a frame against 0.45).
//!
//! **Layout.** `Q`'s columns in groups of `G` (at most 12, as even as possible: m = 20 is two
//! groups of 10), stored block by block: for each block of 8 channels the group's `G` column
//! blocks follow one another, so each pass is one sequential stream. Projection: one load of
//! `c`'s block feeds `G` multiply-adds into `G` accumulators (enough independent chains to
//! hide the 4-cycle latency). Resynthesis: per block, one load of the mean or of `out`, `G`
//! multiply-adds, one store.
//!
//! Left to the autovectoriser, accumulators of 20 or 24 floats in arrays were split and
//! spilled to the stack (2-4 µs a frame at m = 20). These run only inside
//! [`pulp::Simd::vectorize`] (through the `WithSimd` operations below), where they are
//! compiled for AVX2 + FMA; everything is `#[inline(always)]` for that reason.

use pulp::x86::V3;
use pulp::{as_arrays, cast, f32x8, Simd as _};

/// Columns of `Q` in a group at most.
const MAX_GROUP: usize = 12;

/// `count` split into the fewest groups of at most `max`, as even as possible: (groups, size).
fn groups(count: usize, max: usize) -> (usize, usize) {
    let groups = count.div_ceil(max).max(1);
    (groups, count.div_ceil(groups).max(1))
}

/// A model's matrices in the layout of these kernels (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct Layout {
    /// Channels.
    channels: usize,
    /// Columns of `Q` per group.
    group: usize,
    /// `Q`, groups of columns, block-interleaved, zero padded.
    q: Vec<f32>,
    /// `R⁻¹`, `R` and `Rᵀ`, column-major, each column zero padded to `small` rows.
    r_inv: Vec<f32>,
    r: Vec<f32>,
    rt: Vec<f32>,
    /// Rows of the padded m x m columns (m rounded up to 8).
    small: usize,
    /// The mean, zero padded to whole blocks.
    mean: Vec<f32>,
    /// Scratch: the centred frame, zero padded; `Qᵀ c`.
    centered: Vec<f32>,
    z: Vec<f32>,
}

impl Layout {
    /// The layout of the model whose mixing matrix is `mixing` (n x m, full column rank) and
    /// mean `mean`; `None` when `R` cannot be inverted in f64.
    pub(crate) fn new(mixing: &nalgebra::DMatrix<f64>, mean: &[f32]) -> Option<Layout> {
        let (n, m) = mixing.shape();
        let qr = mixing.clone().qr();
        let (q, r) = (qr.q(), qr.r());
        let r_inv = r.clone().try_inverse()?;
        let blocks = n.div_ceil(8);
        let (count, group) = groups(m, MAX_GROUP);
        let mut stored = Vec::with_capacity(count * blocks * group * 8);
        for g in 0..count {
            for b in 0..blocks {
                for c in 0..group {
                    let k = g * group + c;
                    stored.extend((0..8).map(|l| {
                        let j = 8 * b + l;
                        if k < m && j < n {
                            q[(j, k)] as f32
                        } else {
                            0.0
                        }
                    }));
                }
            }
        }
        let small = m.div_ceil(8) * 8;
        let columns = |a: &nalgebra::DMatrix<f64>| -> Vec<f32> {
            (0..m)
                .flat_map(|k| (0..small).map(move |i| if i < m { a[(i, k)] as f32 } else { 0.0 }))
                .collect()
        };
        let mut padded = mean.to_vec();
        padded.resize(blocks * 8, 0.0);
        Some(Layout {
            channels: n,
            group,
            q: stored,
            r_inv: columns(&r_inv),
            r: columns(&r),
            rt: columns(&r.transpose()),
            small,
            mean: padded,
            centered: vec![0.0; blocks * 8],
            z: vec![0.0; count * group],
        })
    }
}

/// `u = R⁻¹ Qᵀ (x − mean)` as a pulp operation.
pub(crate) struct Project<'a> {
    pub(crate) v3: V3,
    pub(crate) layout: &'a mut Layout,
    pub(crate) x: &'a [f32],
    pub(crate) u: &'a mut [f32],
}

impl pulp::WithSimd for Project<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let Project { v3, layout, x, u } = self;
        let n = layout.channels;
        // c = x − mean over whole vectors, then the tail.
        let (xs, x_tail) = as_arrays::<8, f32>(x);
        let (means, _) = as_arrays::<8, f32>(&layout.mean);
        let (cs, _) = pulp::as_arrays_mut::<8, f32>(&mut layout.centered);
        for ((c, x), m) in cs.iter_mut().zip(xs).zip(means) {
            *c = cast(v3.sub_f32x8(cast(*x), cast(*m)));
        }
        let full = n - x_tail.len();
        for (j, &xj) in x_tail.iter().enumerate() {
            layout.centered[full + j] = xj - layout.mean[full + j];
        }
        let (q, c, z) = (&layout.q, &layout.centered, &mut layout.z);
        match layout.group {
            1 => project::<1>(v3, q, c, z),
            2 => project::<2>(v3, q, c, z),
            3 => project::<3>(v3, q, c, z),
            4 => project::<4>(v3, q, c, z),
            5 => project::<5>(v3, q, c, z),
            6 => project::<6>(v3, q, c, z),
            7 => project::<7>(v3, q, c, z),
            8 => project::<8>(v3, q, c, z),
            9 => project::<9>(v3, q, c, z),
            10 => project::<10>(v3, q, c, z),
            11 => project::<11>(v3, q, c, z),
            _ => project::<12>(v3, q, c, z),
        }
        small_gemv(v3, &layout.r_inv, layout.small, &layout.z[..u.len()], u);
    }
}

/// The masked solve's right-hand side `Mᵀc = Rᵀ(Qᵀc)` of a centred frame `c` (missing
/// channels zeroed), as a pulp operation.
pub(crate) struct Normal<'a> {
    pub(crate) v3: V3,
    pub(crate) layout: &'a mut Layout,
    pub(crate) c: &'a [f32],
    pub(crate) rhs: &'a mut [f64],
}

impl pulp::WithSimd for Normal<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let Normal { v3, layout, c, rhs } = self;
        layout.centered[..c.len()].copy_from_slice(c);
        let (q, c, z) = (&layout.q, &layout.centered, &mut layout.z);
        match layout.group {
            1 => project::<1>(v3, q, c, z),
            2 => project::<2>(v3, q, c, z),
            3 => project::<3>(v3, q, c, z),
            4 => project::<4>(v3, q, c, z),
            5 => project::<5>(v3, q, c, z),
            6 => project::<6>(v3, q, c, z),
            7 => project::<7>(v3, q, c, z),
            8 => project::<8>(v3, q, c, z),
            9 => project::<9>(v3, q, c, z),
            10 => project::<10>(v3, q, c, z),
            11 => project::<11>(v3, q, c, z),
            _ => project::<12>(v3, q, c, z),
        }
        let m = rhs.len();
        let mut out = [0.0_f32; 32];
        small_gemv(v3, &layout.rt, layout.small, &layout.z[..m], &mut out[..m]);
        for (r, o) in rhs.iter_mut().zip(out) {
            *r = f64::from(o);
        }
    }
}

/// `out = a z` for `a` m x m, column-major with columns of `rows` floats (m rounded up to 8,
/// zero padded): dispatched on the vectors per column.
#[inline(always)]
fn small_gemv(v3: V3, a: &[f32], rows: usize, z: &[f32], out: &mut [f32]) {
    match rows / 8 {
        1 => small::<1>(v3, a, z, out),
        2 => small::<2>(v3, a, z, out),
        3 => small::<3>(v3, a, z, out),
        _ => small::<4>(v3, a, z, out),
    }
}

/// [`small_gemv`] for columns of `V` vectors: columns in pairs into two accumulators, so two
/// chains of multiply-adds run at once.
#[inline(always)]
fn small<const V: usize>(v3: V3, a: &[f32], z: &[f32], out: &mut [f32]) {
    let zero = v3.splat_f32x8(0.0);
    let (mut even, mut odd) = ([zero; V], [zero; V]);
    let (a, _) = as_arrays::<8, f32>(a);
    let columns = a.chunks_exact(V);
    let mut pairs = columns
        .clone()
        .zip(z)
        .step_by(2)
        .zip(columns.skip(1).zip(z.iter().skip(1)).step_by(2));
    for ((c0, &z0), (c1, &z1)) in &mut pairs {
        let (s0, s1) = (v3.splat_f32x8(z0), v3.splat_f32x8(z1));
        for r in 0..V {
            even[r] = v3.mul_add_f32x8(s0, cast(c0[r]), even[r]);
            odd[r] = v3.mul_add_f32x8(s1, cast(c1[r]), odd[r]);
        }
    }
    if z.len() % 2 == 1 {
        let k = z.len() - 1;
        let s = v3.splat_f32x8(z[k]);
        let col = &a[k * V..(k + 1) * V];
        for r in 0..V {
            even[r] = v3.mul_add_f32x8(s, cast(col[r]), even[r]);
        }
    }
    // A masked store for the last, partial vector: a slice copy of a length known only at
    // run time is a call to memmove, 4 % of a frame.
    for (r, o) in out.chunks_mut(8).enumerate().take(V) {
        v3.partial_store_f32s(o, v3.add_f32x8(even[r], odd[r]));
    }
}

/// `z = Qᵀ c` for the block-interleaved groups of `G` columns in `q`.
#[inline(always)]
fn project<const G: usize>(v3: V3, w: &[f32], c: &[f32], u: &mut [f32]) {
    let (cs, _) = as_arrays::<8, f32>(c);
    let (w, _) = as_arrays::<8, f32>(w);
    let zero = v3.splat_f32x8(0.0);
    for (group, out) in w.chunks_exact(cs.len() * G).zip(u.chunks_mut(G)) {
        let mut acc = [zero; G];
        for (rows, c) in group.chunks_exact(G).zip(cs) {
            let c: f32x8 = cast(*c);
            for i in 0..G {
                acc[i] = v3.mul_add_f32x8(cast(rows[i]), c, acc[i]);
            }
        }
        for (o, a) in out.iter_mut().zip(acc) {
            *o = v3.reduce_sum_f32s(a);
        }
    }
}

/// `out = mean + Q R u` as a pulp operation.
pub(crate) struct Resynth<'a> {
    pub(crate) v3: V3,
    pub(crate) layout: &'a Layout,
    pub(crate) u: &'a [f32],
    pub(crate) out: &'a mut [f32],
}

impl pulp::WithSimd for Resynth<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let Resynth { v3, layout, u, out } = self;
        // y = R u, on the stack (m ≤ 32 in this layout).
        let mut y = [0.0_f32; 32];
        small_gemv(v3, &layout.r, layout.small, u, &mut y[..u.len()]);
        let (q, mean, y) = (&layout.q, &layout.mean, &y[..u.len()]);
        match layout.group {
            1 => resynth::<1>(v3, q, y, mean, out),
            2 => resynth::<2>(v3, q, y, mean, out),
            3 => resynth::<3>(v3, q, y, mean, out),
            4 => resynth::<4>(v3, q, y, mean, out),
            5 => resynth::<5>(v3, q, y, mean, out),
            6 => resynth::<6>(v3, q, y, mean, out),
            7 => resynth::<7>(v3, q, y, mean, out),
            8 => resynth::<8>(v3, q, y, mean, out),
            9 => resynth::<9>(v3, q, y, mean, out),
            10 => resynth::<10>(v3, q, y, mean, out),
            11 => resynth::<11>(v3, q, y, mean, out),
            _ => resynth::<12>(v3, q, y, mean, out),
        }
    }
}

/// `out = mean + Q y` for the block-interleaved groups of `H` columns in `mixing` (`y` read
/// as zero past its end, as the padding columns are): per block of 8 channels, the mean
/// (first group) or `out`, `H` multiply-adds, one store ([`sum_blocks`]).
#[inline(always)]
fn resynth<const H: usize>(v3: V3, mixing: &[f32], u: &[f32], mean: &[f32], out: &mut [f32]) {
    let (means, _) = as_arrays::<8, f32>(mean);
    let (mixing, _) = as_arrays::<8, f32>(mixing);
    let blocks = means.len();
    let full = out.len() / 8;
    for (g, group) in mixing.chunks_exact(blocks * H).enumerate() {
        let a: [f32x8; H] =
            std::array::from_fn(|i| v3.splat_f32x8(u.get(g * H + i).copied().unwrap_or(0.0)));
        let (outs, tail) = pulp::as_arrays_mut::<8, f32>(out);
        // Four blocks at a time, then one (see `sum_blocks`).
        let quads = full / 4 * 4;
        let (cols4, cols1) = group[..full * H].split_at(quads * H);
        let (outs4, outs1) = outs.split_at_mut(quads);
        let (means4, means1) = means.split_at(quads);
        let base = |means| if g == 0 { Some(means) } else { None };
        sum_blocks::<H, 4>(v3, &a, cols4, outs4, base(means4));
        sum_blocks::<H, 1>(v3, &a, cols1, outs1, base(means1));
        if !tail.is_empty() {
            // The last, partial block through a local one.
            let mut last = [[0.0f32; 8]];
            last[0][..tail.len()].copy_from_slice(tail);
            let cols = &group[full * H..(full + 1) * H];
            sum_blocks::<H, 1>(v3, &a, cols, &mut last, base(&means[full..full + 1]));
            let len = tail.len();
            tail.copy_from_slice(&last[0][..len]);
        }
    }
}

/// `out = base + Σ_i a_i cols_i` for whole blocks of 8 channels (`cols`: each block's `H`
/// columns in turn), `B` blocks at a time with their sums' chains interleaved: one block's
/// chain of `H` dependent multiply-adds alone leaves the FMA pipes waiting on its latency
/// (Zen 1 splits each 256-bit operation in two and holds fewer in flight). Each block's sum is
/// taken in the same order whatever `B`, so the result is the same to the bit. The group's sum
/// comes first, then onto the mean (`base`, the first group) or `out` (coordinates of a metre or
/// so): one rounding at their scale per group, not one per column.
#[inline(always)]
fn sum_blocks<const H: usize, const B: usize>(
    v3: V3,
    a: &[f32x8; H],
    cols: &[[f32; 8]],
    outs: &mut [[f32; 8]],
    base: Option<&[[f32; 8]]>,
) {
    let zero = v3.splat_f32x8(0.0);
    for (k, (cols, o)) in cols
        .chunks_exact(B * H)
        .zip(outs.chunks_exact_mut(B))
        .enumerate()
    {
        let mut s = [zero; B];
        for i in 0..H {
            for (j, s) in s.iter_mut().enumerate() {
                *s = v3.mul_add_f32x8(a[i], cast(cols[j * H + i]), *s);
            }
        }
        for j in 0..B {
            let onto = base.map_or(o[j], |m| m[k * B + j]);
            o[j] = cast(v3.add_f32x8(cast(onto), s[j]));
        }
    }
}
