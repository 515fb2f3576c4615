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
