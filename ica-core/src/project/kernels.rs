//! The f32 inner loops of the frame path, written so the compiler vectorises them without
//! `unsafe` or target-specific code: fixed-width lane arrays for reductions (a plain `sum`
//! is a serial chain, since float addition is not associative) and element-wise loops over
//! zipped slices (no bounds checks) for updates.
//!
//! **Instruction set.** A portable build targets SSE2: four lanes and a multiply and an add
//! per term. [`Simd`] detects AVX2 with FMA once (at [`super::Projector::new`]) and runs a
//! [`Kernel`] compiled for it through `pulp` (the SIMD dispatch faer uses, already in the
//! tree): the kernels are `#[inline(always)]`, so inside pulp's target-feature function they
//! are vectorised eight lanes wide, and they are generic over [`MulAdd`] so that there each
//! term is one fused multiply-add. Elsewhere the same source runs with a plain multiply and
//! add (a fused one without hardware support is a slow library call).

/// How `a · b + c` is computed.
pub(crate) trait MulAdd: Copy {
    /// `a · b + c`.
    fn mul_add(a: f32, b: f32, c: f32) -> f32;
    /// `a · b + c` in f64.
    fn mul_add64(a: f64, b: f64, c: f64) -> f64;
}

/// One fused multiply-add (one rounding): only where the CPU has FMA.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Fused;

impl MulAdd for Fused {
    #[inline(always)]
    fn mul_add(a: f32, b: f32, c: f32) -> f32 {
        a.mul_add(b, c)
    }
    #[inline(always)]
    fn mul_add64(a: f64, b: f64, c: f64) -> f64 {
        a.mul_add(b, c)
    }
}

/// A multiply, then an add.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Plain;

impl MulAdd for Plain {
    #[inline(always)]
    fn mul_add(a: f32, b: f32, c: f32) -> f32 {
        a * b + c
    }
    #[inline(always)]
    fn mul_add64(a: f64, b: f64, c: f64) -> f64 {
        a * b + c
    }
}

/// A computation over frame buffers, run by [`Simd::run`] with the CPU's best instructions.
pub(crate) trait Kernel {
    /// What it returns.
    type Output;
    /// Runs it with multiply-adds done as `A` does them.
    fn run<A: MulAdd>(self) -> Self::Output;
}

/// The instruction set detected for the frame kernels.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Simd {
    #[cfg(target_arch = "x86_64")]
    v3: Option<pulp::x86::V3>,
}

impl Simd {
    /// Detects AVX2 + FMA (x86-64-v3).
    pub(crate) fn detect() -> Simd {
        Simd {
            #[cfg(target_arch = "x86_64")]
            v3: pulp::x86::V3::try_new(),
        }
    }

    /// Runs `kernel`, compiled for AVX2 + FMA when the CPU has them.
    #[inline(always)]
    pub(crate) fn run<K: Kernel>(self, kernel: K) -> K::Output {
        #[cfg(target_arch = "x86_64")]
        if let Some(v3) = self.v3 {
            return pulp::Simd::vectorize(v3, RunFused(kernel));
        }
        kernel.run::<Plain>()
    }

    /// `u = W (x − mean)` from `w`, m rows of `stride` floats; `centered` is scratch.
    pub(crate) fn rows_gemv(
        self,
        w: &[f32],
        stride: usize,
        x: &[f32],
        mean: &[f32],
        centered: &mut [f32],
        u: &mut [f32],
    ) {
        self.run(Rows {
            w,
            stride,
            x,
            mean,
            centered,
            u,
        });
    }

    /// `u = W (x − mean)` from the panel `wt` (`Wᵀ`, n rows of `width` floats, a multiple of 8
    /// up to 32; see [`panel_width`]).
    pub(crate) fn panel_gemv(
        self,
        wt: &[f32],
        width: usize,
        x: &[f32],
        mean: &[f32],
        u: &mut [f32],
    ) {
        match width {
            8 => panel_gemv::<8, Plain>(wt, x, mean, u),
            16 => panel_gemv::<16, Plain>(wt, x, mean, u),
            24 => panel_gemv::<24, Plain>(wt, x, mean, u),
            _ => panel_gemv::<32, Plain>(wt, x, mean, u),
        }
    }

    /// `out = mean + M u`, `M` column-major.
    pub(crate) fn resynth(self, mixing: &[f32], mean: &[f32], u: &[f32], out: &mut [f32]) {
        self.run(Resynth {
            mixing,
            mean,
            u,
            out,
        });
    }
}

/// `u = W (x − mean)` in the row layout: m dot products.
struct Rows<'a> {
    w: &'a [f32],
    stride: usize,
    x: &'a [f32],
    mean: &'a [f32],
    centered: &'a mut [f32],
    u: &'a mut [f32],
}

impl Kernel for Rows<'_> {
    type Output = ();
    #[inline(always)]
    fn run<A: MulAdd>(self) {
        let c = &mut self.centered[..self.x.len()];
        sub_into(self.x, self.mean, c);
        for (row, o) in self.w.chunks_exact(self.stride).zip(self.u.iter_mut()) {
            *o = dot::<A>(row, c);
        }
    }
}

/// [`resynth`] as a kernel.
struct Resynth<'a> {
    mixing: &'a [f32],
    mean: &'a [f32],
    u: &'a [f32],
    out: &'a mut [f32],
}

impl Kernel for Resynth<'_> {
    type Output = ();
    #[inline(always)]
    fn run<A: MulAdd>(self) {
        resynth::<A>(self.mixing, self.mean, self.u, self.out);
    }
}

/// The panel width for `m` components: the multiple of 8 (one AVX register) at or above it,
/// up to 32; 0 (the row layout) beyond.
pub(crate) fn panel_width(m: usize) -> usize {
    if m <= 32 {
        m.div_ceil(8).max(1) * 8
    } else {
        0
    }
}

/// `out = mean + M u`, `M` column-major: columns four at a time, the first four starting from
/// the mean.
#[inline(always)]
pub(crate) fn resynth<A: MulAdd>(mixing: &[f32], mean: &[f32], u: &[f32], out: &mut [f32]) {
    let n = out.len();
    let mut cols = mixing.chunks_exact(4 * n);
    let mut uk = u.chunks_exact(4);
    if u.len() < 4 {
        out.copy_from_slice(mean);
    }
    for (i, (block, a)) in (&mut cols).zip(&mut uk).enumerate() {
        let (c0, rest) = block.split_at(n);
        let (c1, rest) = rest.split_at(n);
        let (c2, c3) = rest.split_at(n);
        let (a, c) = ([a[0], a[1], a[2], a[3]], [c0, c1, c2, c3]);
        if i == 0 {
            axpy4_onto::<A>(mean, a, c, out);
        } else {
            axpy4::<A>(a, c, out);
        }
    }
    for (col, &a) in cols.remainder().chunks_exact(n).zip(uk.remainder()) {
        axpy::<A>(a, col, out);
    }
}

/// A [`Kernel`] with fused multiply-adds, as pulp runs an operation: `with_simd` is
/// `#[inline(always)]`, so the kernel is compiled inside pulp's AVX2 + FMA function (a closure
/// there may stay a call of its own, compiled without them).
#[cfg(target_arch = "x86_64")]
struct RunFused<K>(K);

#[cfg(target_arch = "x86_64")]
impl<K: Kernel> pulp::WithSimd for RunFused<K> {
    type Output = K::Output;
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> K::Output {
        self.0.run::<Fused>()
    }
}

/// Lanes per reduction: four SSE or two AVX registers, enough independent adds to hide
/// latency.
const LANES: usize = 16;

/// `Σ a_i b_i` over the shorter of the two slices.
#[inline(always)]
pub(crate) fn dot<A: MulAdd>(a: &[f32], b: &[f32]) -> f32 {
    let ca = a.chunks_exact(LANES);
    let cb = b.chunks_exact(LANES);
    let mut tail = 0.0_f32;
    for (x, y) in ca.remainder().iter().zip(cb.remainder()) {
        tail = A::mul_add(*x, *y, tail);
    }
    let mut acc = [0.0_f32; LANES];
    for (x, y) in ca.zip(cb) {
        for i in 0..LANES {
            acc[i] = A::mul_add(x[i], y[i], acc[i]);
        }
    }
    reduce(acc) + tail
}

/// `u = W (x − mean)` for `wt` = `Wᵀ` as n rows of `K` (zero padded from `u.len()` to `K`
/// columns): `acc += (x_j − mean_j) · wt[j]`, even and odd rows into two accumulators (with
/// one, every row would wait on the previous row's add). The portable kernel; on AVX2 + FMA
/// [`super::avx2::panel_gemv`] runs instead.
#[inline(always)]
pub(crate) fn panel_gemv<const K: usize, A: MulAdd>(
    wt: &[f32],
    x: &[f32],
    mean: &[f32],
    u: &mut [f32],
) {
    let (mut even, mut odd) = ([0.0_f32; K], [0.0_f32; K]);
    let rows = wt.chunks_exact(2 * K);
    let last = rows.remainder();
    let (xs, ms) = (x.chunks_exact(2), mean.chunks_exact(2));
    let (x_last, m_last) = (xs.remainder(), ms.remainder());
    for ((pair, xp), mp) in rows.zip(xs).zip(ms) {
        let (c0, c1) = (xp[0] - mp[0], xp[1] - mp[1]);
        let (r0, r1) = pair.split_at(K);
        for i in 0..K {
            even[i] = A::mul_add(c0, r0[i], even[i]);
            odd[i] = A::mul_add(c1, r1[i], odd[i]);
        }
    }
    if let (Some(&xj), Some(&mj)) = (x_last.first(), m_last.first()) {
        for i in 0..K {
            even[i] = A::mul_add(xj - mj, last[i], even[i]);
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
#[inline(always)]
pub(crate) fn axpy<A: MulAdd>(a: f32, x: &[f32], y: &mut [f32]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi = A::mul_add(a, *xi, *yi);
    }
}

/// `y += a0 x0 + a1 x1 + a2 x2 + a3 x3`: one pass over `y` for four columns, so `y` is
/// loaded and stored a quarter as often as with four [`axpy`] calls.
#[inline(always)]
pub(crate) fn axpy4<A: MulAdd>(a: [f32; 4], x: [&[f32]; 4], y: &mut [f32]) {
    let n = y.len();
    let (x0, x1, x2, x3) = (&x[0][..n], &x[1][..n], &x[2][..n], &x[3][..n]);
    for j in 0..n {
        // The four terms first, then onto `y` (coordinates of a metre or so): one rounding at
        // its scale per four columns.
        let s = A::mul_add(a[1], x1[j], a[0] * x0[j]);
        let s = A::mul_add(a[2], x2[j], s);
        y[j] += A::mul_add(a[3], x3[j], s);
    }
}

/// `y = base + a0 x0 + a1 x1 + a2 x2 + a3 x3`: [`axpy4`] that starts from `base` instead of
/// reading `y`, so resynthesis needs no separate copy of the mean (one pass over `y` fewer).
#[inline(always)]
pub(crate) fn axpy4_onto<A: MulAdd>(base: &[f32], a: [f32; 4], x: [&[f32]; 4], y: &mut [f32]) {
    let n = y.len();
    let (b, x0, x1, x2, x3) = (&base[..n], &x[0][..n], &x[1][..n], &x[2][..n], &x[3][..n]);
    for j in 0..n {
        // as axpy4 from a copy of `base`: bit-identical results
        let s = A::mul_add(a[1], x1[j], a[0] * x0[j]);
        let s = A::mul_add(a[2], x2[j], s);
        y[j] = b[j] + A::mul_add(a[3], x3[j], s);
    }
}

/// `out = a - b`.
#[inline(always)]
pub(crate) fn sub_into(a: &[f32], b: &[f32], out: &mut [f32]) {
    for ((o, ai), bi) in out.iter_mut().zip(a).zip(b) {
        *o = ai - bi;
    }
}

#[cfg(test)]
mod tests;
