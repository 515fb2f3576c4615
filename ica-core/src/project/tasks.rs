//! The per-frame loops as [`Kernel`] tasks, so each runs under the SIMD dispatch chosen at
//! [`super::Projector::new`] (with fused multiply-adds where the CPU has them).

use super::kernels::{self, axpy, Kernel, MulAdd};
use super::masked::{self, MaskedSolver};

/// The masked solve as a kernel (its f64 loops vectorised, with fused multiply-adds where
/// the CPU has them).
pub(super) struct MaskedSolve<'a> {
    pub(super) solver: &'a mut MaskedSolver,
    pub(super) hidden_count: usize,
    pub(super) prior: &'a [f32],
    pub(super) u: &'a mut [f32],
}

impl Kernel for MaskedSolve<'_> {
    type Output = masked::Solve;
    #[inline(always)]
    fn run<A: MulAdd>(self) -> masked::Solve {
        self.solver
            .solve::<A>(self.hidden_count, self.prior, self.u)
    }
}

/// `Mᵀc` of the centred frame `c` (missing channels zeroed) as a kernel.
pub(super) struct NormalRhs<'a> {
    pub(super) mixing: &'a [f32],
    pub(super) centered: &'a [f32],
    pub(super) rhs: &'a mut [f64],
}

impl Kernel for NormalRhs<'_> {
    type Output = ();
    #[inline(always)]
    fn run<A: MulAdd>(self) {
        let n = self.centered.len();
        for (r, col) in self.rhs.iter_mut().zip(self.mixing.chunks_exact(n)) {
            *r = f64::from(kernels::dot::<A>(col, self.centered));
        }
    }
}

/// `y += a x` as a kernel.
pub(super) struct Axpy<'a> {
    pub(super) a: f32,
    pub(super) x: &'a [f32],
    pub(super) y: &'a mut [f32],
}

impl Kernel for Axpy<'_> {
    type Output = ();
    #[inline(always)]
    fn run<A: MulAdd>(self) {
        axpy::<A>(self.a, self.x, self.y);
    }
}

/// `centered = x − mean` with the channels of the hidden markers (flagged in `missing`, or
/// with a non-finite coordinate) zeroed, so that `Mᵀc` sums the observed rows only; marks
/// them in `hidden` and returns how many. No branch per marker (real occlusions are
/// irregular): the subtraction and the finiteness check are whole-frame vector loops, and
/// only the hidden markers are visited to be zeroed.
pub(super) struct CenterVisible<'a> {
    pub(super) x: &'a [f32],
    pub(super) mean: &'a [f32],
    pub(super) missing: Option<&'a [bool]>,
    pub(super) centered: &'a mut [f32],
    pub(super) hidden: &'a mut [bool],
    /// Scratch of one index per marker.
    pub(super) gone: &'a mut [usize],
}

impl Kernel for CenterVisible<'_> {
    type Output = usize;
    #[inline(always)]
    fn run<A: MulAdd>(self) -> usize {
        let CenterVisible {
            x,
            mean,
            missing,
            centered,
            hidden,
            gone,
        } = self;
        kernels::sub_into(x, mean, centered);
        let all_finite = centered.iter().fold(true, |ok, v| ok & v.is_finite());
        match missing {
            Some(mask) if all_finite => hidden.copy_from_slice(mask),
            _ => {
                let flags = missing.into_iter().flatten().copied();
                let flags = flags.chain(std::iter::repeat(false));
                for ((h, c), flag) in hidden.iter_mut().zip(centered.chunks_exact(3)).zip(flags) {
                    *h = flag | !(c[0].is_finite() & c[1].is_finite() & c[2].is_finite());
                }
            }
        }
        let mut count = 0;
        for (i, &h) in hidden.iter().enumerate() {
            gone[count] = i;
            count += usize::from(h);
        }
        for &i in &gone[..count] {
            centered[3 * i..3 * i + 3].fill(0.0);
        }
        count
    }
}
