//! The fixed-point update's sums over whitened frames in one fused pass, for
//! [`super::UpdateAccumulator`]: per frame the sources `y = W z`, `g(y)` and `Σ g'(y)`; then
//! `B += Σ z g(y)ᵀ` over a tile of frames.
//!
//! Two general matrix products per block (through matrixmultiply) packed both operands on
//! every call and ran the contrast in a separate loop at baseline x86-64: with `m = 20` each
//! product is too thin for a packed kernel to pay. On a 1-hour session that update was 41 % of
//! `train`'s CPU (perf), 17 points of it the contrast loop and about 8 the packing. Here:
//! - **Layout.** `Wᵀ` row by row, each row (`k` values) zero padded to whole vectors of 4, so
//!   a frame's sources are `m` broadcast multiply-adds into at most [`TILE`] accumulators per
//!   tile of the row. The padded lanes stay 0 through the sources and `g`, so they add nothing
//!   to `B`; their `g'` sums are dropped.
//! - **Tiles of [`TILE_FRAMES`] frames**, whose frames and `g` (2 x 20 KB at `m = k = 20`)
//!   stay in L1 while `B`'s rows are swept two at a time.
//! - **AVX2 + FMA** through pulp where the CPU has them (x86-64-v3), as in
//!   [`crate::project`]; elsewhere the same loops in scalar code. `tanh` is [`tanh_f32`](super::contrast::tanh_f32)'s
//!   rational function lane for lane, with the same operations in the same order, so `g`
//!   is bit-identical to the scalar contrast; the sums differ from a packed product's at
//!   rounding level only (another summation order, and fused multiply-adds).

use nalgebra::DMatrix;
use pulp::x86::V3;
use pulp::{as_arrays, as_arrays_mut, cast, f64x4};

use super::contrast::{TANH_CLAMP, TANH_P, TANH_Q};
use super::Contrast;

/// Frames whose sources and `g` are made before `B` is swept over them.
const TILE_FRAMES: usize = 128;
/// Vectors of accumulators in one tile of a row (the rest of 16 registers: broadcasts, loads).
const TILE: usize = 6;

/// Runs `$call` once per tile of at most [`TILE`] of the `$kv` vectors, with `$v0` the tile's
/// first vector and `$t` its width as a constant (so the accumulators are a fixed-size array).
macro_rules! for_each_tile {
    ($kv:expr, $v0:ident, $t:ident => $call:expr) => {{
        let kv = $kv;
        let mut $v0 = 0;
        while $v0 < kv {
            let width = (kv - $v0).min(TILE);
            for_each_tile!(@widths width, $t => $call; 1 2 3 4 5);
            $v0 += width;
        }
    }};
    (@widths $width:ident, $t:ident => $call:expr; $($n:literal)*) => {
        match $width {
            $($n => {
                const $t: usize = $n;
                $call
            })*
            _ => {
                const $t: usize = TILE;
                $call
            }
        }
    };
}

/// The rotation in this kernel's layout and the sums so far (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct Fused {
    m: usize,
    k: usize,
    /// `k` rounded up to whole vectors of 4.
    kp: usize,
    /// `Wᵀ`, `m` rows of `kp`.
    wt: Vec<f64>,
    /// `Σ z g(y)ᵀ`, `m` rows of `kp`.
    bt: Vec<f64>,
    /// `Σ g'(y)` per lane, `kp`.
    gp: Vec<f64>,
    /// Scratch: a tile's `g`, `TILE_FRAMES` rows of `kp`.
    g: Vec<f64>,
    v3: Option<V3>,
}

impl Fused {
    /// Empty sums for `w` (`k x m`).
    pub(crate) fn new(w: &DMatrix<f64>) -> Self {
        let (k, m) = w.shape();
        let kp = k.div_ceil(4).max(1) * 4;
        let mut wt = vec![0.0; m * kp];
        for (row, column) in wt.chunks_exact_mut(kp).zip(w.column_iter()) {
            row[..k].copy_from_slice(column.as_slice());
        }
        Self {
            m,
            k,
            kp,
            wt,
            bt: vec![0.0; m * kp],
            gp: vec![0.0; kp],
            g: vec![0.0; TILE_FRAMES * kp],
            v3: V3::try_new(),
        }
    }

    /// Adds whole frames of `m` values (f64, frame after frame).
    pub(crate) fn add(&mut self, z: &[f64], contrast: Contrast) {
        for tile in z.chunks(TILE_FRAMES * self.m.max(1)) {
            match self.v3 {
                Some(v3) => pulp::Simd::vectorize(
                    v3,
                    Tile {
                        v3,
                        sums: self,
                        z: tile,
                        contrast,
                    },
                ),
                None => self.add_scalar(tile, contrast),
            }
        }
    }

    /// Adds the sums of `other` (made for the same rotation).
    pub(crate) fn merge(&mut self, other: &Fused) {
        for (a, b) in self.bt.iter_mut().zip(&other.bt) {
            *a += b;
        }
        for (a, b) in self.gp.iter_mut().zip(&other.gp) {
            *a += b;
        }
    }

    /// `B = Σ z g(y)ᵀ` (`m x k`) and `Σ g'(y)` per row of `W`.
    pub(crate) fn sums(&self) -> (DMatrix<f64>, Vec<f64>) {
        let b = DMatrix::from_fn(self.m, self.k, |j, i| self.bt[j * self.kp + i]);
        (b, self.gp[..self.k].to_vec())
    }

    /// The same sums without SIMD.
    fn add_scalar(&mut self, z: &[f64], contrast: Contrast) {
        let (m, kp) = (self.m, self.kp);
        for (zt, gt) in z.chunks_exact(m).zip(self.g.chunks_exact_mut(kp)) {
            gt.fill(0.0);
            for (&zj, row) in zt.iter().zip(self.wt.chunks_exact(kp)) {
                gt.iter_mut().zip(row).for_each(|(y, w)| *y += zj * w);
            }
            for (y, s) in gt.iter_mut().zip(self.gp.iter_mut()) {
                let (g, dg) = contrast.pair(*y);
                *y = g;
                *s += dg;
            }
        }
        for (zt, gt) in z.chunks_exact(m).zip(self.g.chunks_exact(kp)) {
            for (&zj, row) in zt.iter().zip(self.bt.chunks_exact_mut(kp)) {
                row.iter_mut().zip(gt).for_each(|(b, g)| *b += zj * g);
            }
        }
    }
}

/// One tile of frames through the AVX2 kernels, as a pulp operation.
struct Tile<'a> {
    v3: V3,
    sums: &'a mut Fused,
    z: &'a [f64],
    contrast: Contrast,
}

impl pulp::WithSimd for Tile<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let Tile {
            v3,
            sums,
            z,
            contrast,
        } = self;
        let (m, kv) = (sums.m, sums.kp / 4);
        let (wt, _) = as_arrays::<4, f64>(&sums.wt);
        let (gs, _) = as_arrays_mut::<4, f64>(&mut sums.g);
        // Two frames at a time: twice the independent multiply-add chains of one.
        let mut pairs = z.chunks_exact(2 * m);
        for (zt, gt) in pairs.by_ref().zip(gs.chunks_exact_mut(2 * kv)) {
            sources::<2>(v3, wt, kv, m, zt, gt);
        }
        let done = z.len() / (2 * m) * 2;
        if let (Some(zt), Some(gt)) = (pairs.remainder().get(..m), gs.get_mut(done * kv..)) {
            sources::<1>(v3, wt, kv, m, zt, gt);
        }
        let (gp, _) = as_arrays_mut::<4, f64>(&mut sums.gp);
        let nb = z.len() / m;
        for gt in gs[..nb * kv].chunks_exact_mut(kv) {
            contrast_lanes(v3, contrast, gt, gp);
        }
        let (bt, _) = as_arrays_mut::<4, f64>(&mut sums.bt);
        let g = &gs[..nb * kv];
        let mut j = 0;
        while j < m {
            if m - j >= 2 {
                for_each_tile!(kv, v0, T => outer_tile::<2, T>(v3, z, m, j, g, kv, v0, bt));
                j += 2;
            } else {
                for_each_tile!(kv, v0, T => outer_tile::<1, T>(v3, z, m, j, g, kv, v0, bt));
                j += 1;
            }
        }
    }
}

/// The sources of `F` frames (`zt`, `F x m`) into `y` (`F x kv` vectors), tile by tile.
#[inline(always)]
fn sources<const F: usize>(
    v3: V3,
    wt: &[[f64; 4]],
    kv: usize,
    m: usize,
    zt: &[f64],
    y: &mut [[f64; 4]],
) {
    for_each_tile!(kv, v0, T => sources_tile::<F, T>(v3, wt, kv, v0, m, zt, y));
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn sources_tile<const F: usize, const T: usize>(
    v3: V3,
    wt: &[[f64; 4]],
    kv: usize,
    v0: usize,
    m: usize,
    zt: &[f64],
    y: &mut [[f64; 4]],
) {
    let mut acc = [[v3.splat_f64x4(0.0); T]; F];
    for j in 0..m {
        let b: [f64x4; F] = std::array::from_fn(|f| v3.splat_f64x4(zt[f * m + j]));
        let row = &wt[j * kv + v0..j * kv + v0 + T];
        for (v, w) in row.iter().enumerate() {
            let w: f64x4 = cast(*w);
            for (a, &b) in acc.iter_mut().zip(&b) {
                a[v] = v3.mul_add_f64x4(b, w, a[v]);
            }
        }
    }
    for (f, frame) in acc.iter().enumerate() {
        for (v, a) in frame.iter().enumerate() {
            y[f * kv + v0 + v] = cast(*a);
        }
    }
}

/// `g` in place of the sources `y`, `g'` added to `gp`, lane for lane.
#[inline(always)]
fn contrast_lanes(v3: V3, contrast: Contrast, y: &mut [[f64; 4]], gp: &mut [[f64; 4]]) {
    let one = v3.splat_f64x4(1.0);
    for (y, s) in y.iter_mut().zip(gp.iter_mut()) {
        let (g, dg) = match contrast {
            Contrast::LogCosh => {
                let t =
                    v3.convert_f32x4_to_f64x4(tanh_f32x4(v3, v3.convert_f64x4_to_f32x4(cast(*y))));
                (t, v3.sub_f64x4(one, v3.mul_f64x4(t, t)))
            }
            _ => {
                let pairs = (*y).map(|v| contrast.pair(v));
                (cast(pairs.map(|p| p.0)), cast(pairs.map(|p| p.1)))
            }
        };
        *y = cast(g);
        *s = cast(v3.add_f64x4(cast(*s), dg));
    }
}

/// [`tanh_f32`](super::contrast::tanh_f32) on 4 lanes, with its operations in its order.
#[inline(always)]
fn tanh_f32x4(v3: V3, x: pulp::f32x4) -> pulp::f32x4 {
    let x = v3.min_f32x4(
        v3.max_f32x4(x, v3.splat_f32x4(-TANH_CLAMP)),
        v3.splat_f32x4(TANH_CLAMP),
    );
    let x2 = v3.mul_f32x4(x, x);
    let mut p = v3.splat_f32x4(TANH_P[0]);
    for &c in &TANH_P[1..] {
        p = v3.add_f32x4(v3.mul_f32x4(p, x2), v3.splat_f32x4(c));
    }
    let mut q = v3.splat_f32x4(TANH_Q[0]);
    for &c in &TANH_Q[1..] {
        q = v3.add_f32x4(v3.mul_f32x4(q, x2), v3.splat_f32x4(c));
    }
    v3.div_f32x4(v3.mul_f32x4(x, p), q)
}

/// `B`'s rows `j..j + R` plus `Σ_t z_t[j + r] g_t` over the tile's frames, for the `T` vectors
/// from `v0`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn outer_tile<const R: usize, const T: usize>(
    v3: V3,
    z: &[f64],
    m: usize,
    j: usize,
    g: &[[f64; 4]],
    kv: usize,
    v0: usize,
    bt: &mut [[f64; 4]],
) {
    let mut acc = [[v3.splat_f64x4(0.0); T]; R];
    for (zt, gt) in z.chunks_exact(m).zip(g.chunks_exact(kv)) {
        let zr: [f64x4; R] = std::array::from_fn(|r| v3.splat_f64x4(zt[j + r]));
        for (v, gv) in gt[v0..v0 + T].iter().enumerate() {
            let gv: f64x4 = cast(*gv);
            for (a, &b) in acc.iter_mut().zip(&zr) {
                a[v] = v3.mul_add_f64x4(b, gv, a[v]);
            }
        }
    }
    for (r, row) in acc.iter().enumerate() {
        for (v, a) in row.iter().enumerate() {
            let b = &mut bt[(j + r) * kv + v0 + v];
            *b = cast(v3.add_f64x4(cast(*b), *a));
        }
    }
}

#[cfg(test)]
mod tests;
