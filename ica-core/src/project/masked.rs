//! Projection of a frame with missing markers: the posterior mean of the model read as a
//! probabilistic PCA, `x = mean + M u + r` with unit-variance components `u` (prior mean
//! `μ`, the last good `u`) and a residual `r` of variance `σ²` per channel (what the kept
//! components leave out, [`IcaModel::residual_variance`](crate::IcaModel::residual_variance)):
//! `(M_oᵀ M_o + σ² I) u = M_oᵀ (x_o − mean_o) + σ² μ` over the observed rows `o`, via a
//! Cholesky factorisation, all in buffers sized at construction. f64 here: squaring `M`
//! squares its condition number, which f32 would not survive.
//!
//! Plain least squares (`σ² = 0`) is exact for a complete frame, where `Mᵀ r = 0`; with rows
//! hidden, `M_oᵀ r_o ≠ 0` and the residual leaks into the components the hidden markers
//! carried most (on Facial-Sing, hiding two cheek markers moved one component by 2.8
//! standard deviations). The prior lets a component follow the data as far as the visible
//! markers determine it and no further.
//!
//! **Observability.** The Cholesky pivot `p_k` of a Gram matrix is the energy of column `k`
//! not explained by columns `0..k`. Hiding rows can only shrink pivots (`M_oᵀM_o ≼ MᵀM`), so
//! `p_k(observed) / p_k(full)` in `[0, 1]` is the share of component `k`'s independent
//! footprint still visible. Its minimum over `k` is the frame's observability; below
//! [`MIN_OBSERVABILITY`] the frame is ill-conditioned and is solved with a ridge that pulls
//! the components toward a prior (the last good `u`, or the mean pose `u = 0`), so what the
//! visible markers determine follows the data and what they cannot see holds still instead
//! of exploding.

/// Observability below which a masked frame is flagged ill-conditioned and regularised
/// (1%: a component whose independent footprint is 99% hidden).
///
/// A frame with missing markers is projected by least squares on the observed rows, through
/// the m x m normal equations and a Cholesky factorisation in f64. Its observability is
/// `min_k p_k(observed) / p_k(full)` over the Cholesky pivots `p_k` (the energy of column `k`
/// of `M` not explained by columns `0..k`), in `[0, 1]` since hiding rows only shrinks
/// pivots. Below this threshold the solve adds a ridge `λ·diag(MᵀM)` (λ = this value) toward
/// the last good components (or 0, the mean pose), so components the visible markers cannot
/// see hold still instead of exploding, while the others follow the data up to a ~1% pull.
pub const MIN_OBSERVABILITY: f64 = 1e-2;

use super::kernels::{MulAdd, Plain};

#[derive(Debug, Clone)]
pub(crate) struct MaskedSolver {
    m: usize,
    /// Each marker's contribution to `MᵀM` (its three rows' outer products), packed lower
    /// triangles back to back: a hidden marker costs one contiguous subtraction of
    /// m(m+1)/2 values instead of three rank-one updates.
    blocks: Vec<f64>,
    gram_full: Vec<f64>,
    pivots_full: Vec<f64>,
    /// Packed lower triangles (row `i` is `[off(i), off(i) + i]`), m x m.
    gram: Vec<f64>,
    /// m x m row-major; its upper triangle is factored in place (`A = UᵀU`).
    factor: Vec<f64>,
    /// The factor's transpose (row-major: `U`'s columns) and its diagonal's reciprocals: both
    /// substitutions then run as row updates, without a division in their chains.
    factor_t: Vec<f64>,
    inv_diag: Vec<f64>,
    pivots: Vec<f64>,
    /// `Mᵀc` for the frame being solved (set by the caller, see [`MaskedSolver::rhs_mut`]).
    rhs: Vec<f64>,
    sol: Vec<f64>,
    /// Per marker: hidden in the frame being solved (see [`MaskedSolver::hidden_mut`]).
    hidden: Vec<bool>,
    /// The hidden set `factor` was built for, and what it found then: occlusions last many
    /// frames, and the factorisation depends on nothing else (the priors' centre `μ` only
    /// enters the right-hand side).
    factored_for: Vec<bool>,
    /// Whether `factored_for` holds a set the factor was built for (not before the first).
    factored_valid: bool,
    factored: Solve,
    /// Residual variance per channel: the prior's weight (0: plain least squares).
    residual_var: f64,
}

/// What a masked solve found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Solve {
    pub observability: f64,
    pub ill_conditioned: bool,
}

/// Start of row `i` in a packed lower triangle.
fn off(i: usize) -> usize {
    i * (i + 1) / 2
}

impl MaskedSolver {
    /// `mixing_rows`: `M` row-major, n x m (n = markers x 3), of full column rank (the model
    /// guarantees it); `residual_var`: the residual variance per channel (mm²).
    pub(crate) fn new(mixing_rows: &[f64], m: usize, residual_var: f64) -> MaskedSolver {
        let tri = off(m);
        let markers = mixing_rows.len() / (3 * m);
        let mut blocks = vec![0.0; markers * tri];
        for (block, rows) in blocks
            .chunks_exact_mut(tri)
            .zip(mixing_rows.chunks_exact(3 * m))
        {
            for row in rows.chunks_exact(m) {
                add_outer(block, row);
            }
        }
        let mut gram_full = vec![0.0; tri];
        for block in blocks.chunks_exact(tri) {
            add_into::<Plain>(&mut gram_full, block, 1.0);
        }
        let mut s = MaskedSolver {
            m,
            blocks,
            gram_full,
            pivots_full: vec![0.0; m],
            gram: vec![0.0; tri],
            factor: vec![0.0; m * m],
            factor_t: vec![0.0; m * m],
            inv_diag: vec![0.0; m],
            pivots: vec![0.0; m],
            rhs: vec![0.0; m],
            sol: vec![0.0; m],
            hidden: vec![false; markers],
            factored_for: vec![false; markers],
            factored_valid: false,
            factored: Solve {
                observability: 1.0,
                ill_conditioned: false,
            },
            residual_var: if residual_var.is_finite() {
                residual_var.max(0.0)
            } else {
                0.0
            },
        };
        unpack(&s.gram_full, &mut s.factor, m);
        let ok = cholesky::<Plain>(&mut s.factor, &mut s.pivots_full, m);
        assert!(
            ok,
            "a full-rank mixing matrix has a positive definite Gram matrix"
        );
        s
    }

    /// Where the caller puts `Mᵀc` for the centred frame `c` with missing channels zeroed
    /// (so it equals `M_oᵀ c_o`), before [`MaskedSolver::solve`].
    pub(crate) fn rhs_mut(&mut self) -> &mut [f64] {
        &mut self.rhs
    }

    /// Where the caller marks the hidden markers, before [`MaskedSolver::solve`].
    pub(crate) fn hidden_mut(&mut self) -> &mut [bool] {
        &mut self.hidden
    }

    /// Solves for `u` given the right-hand side and hidden markers set through
    /// [`MaskedSolver::rhs_mut`] and [`MaskedSolver::hidden_mut`] (`hidden_count` of them),
    /// and the `prior` used when the frame is ill-conditioned; multiply-adds as `A` does them.
    #[inline(always)]
    pub(crate) fn solve<A: MulAdd>(
        &mut self,
        hidden_count: usize,
        prior: &[f32],
        u: &mut [f32],
    ) -> Solve {
        if !(self.factored_valid && self.factored_for == self.hidden) {
            self.factored = self.factor_for_hidden::<A>(hidden_count);
            self.factored_for.copy_from_slice(&self.hidden);
            self.factored_valid = true;
        }
        let Solve {
            observability: _,
            ill_conditioned,
        } = self.factored;
        if self.residual_var > 0.0 || ill_conditioned {
            let ridge = if ill_conditioned {
                MIN_OBSERVABILITY
            } else {
                0.0
            };
            for (k, (r, &p)) in self.rhs.iter_mut().zip(prior).enumerate() {
                let d = self.residual_var + ridge * self.gram_full[off(k) + k];
                *r += d * f64::from(p);
            }
        }
        solve_factored::<A>(
            &self.factor,
            &self.factor_t,
            &self.inv_diag,
            &self.rhs,
            &mut self.sol,
        );
        for (ui, s) in u.iter_mut().zip(&self.sol) {
            *ui = *s as f32;
        }
        self.factored
    }

    /// Builds and factors the system of the current hidden set: the observability from the
    /// data's own Gram matrix, then the factor the solve uses (with the priors, see
    /// [`MaskedSolver::add_priors`]). Where the factorisation was too costly to repeat per frame
    /// (2-3 µs at m = 20), a change of occlusion now pays it once.
    #[inline(always)]
    fn factor_for_hidden<A: MulAdd>(&mut self, hidden_count: usize) -> Solve {
        let m = self.m;
        self.build_gram::<A>(hidden_count);
        unpack(&self.gram, &mut self.factor, m);
        // Observability is measured on the data alone; the solve then adds the priors.
        let ok = cholesky::<A>(&mut self.factor, &mut self.pivots, m);
        let observability = if ok {
            self.pivots
                .iter()
                .zip(&self.pivots_full)
                .map(|(p, f)| p / f)
                .fold(1.0, f64::min)
        } else {
            0.0
        };
        let ill_conditioned = observability < MIN_OBSERVABILITY;
        let ridge = if ill_conditioned {
            MIN_OBSERVABILITY
        } else {
            0.0
        };
        if self.residual_var > 0.0 || ridge > 0.0 {
            self.add_priors::<A>(ridge);
        }
        for i in 0..m {
            self.inv_diag[i] = 1.0 / self.factor[i * m + i];
            for k in i..m {
                self.factor_t[k * m + i] = self.factor[i * m + k];
            }
        }
        Solve {
            observability: observability.max(0.0),
            ill_conditioned,
        }
    }

    /// `M_oᵀ M_o`, by subtracting the hidden markers' blocks from the full Gram when they are
    /// the minority (cheap for a few occluded markers) and by summing the observed blocks
    /// otherwise (the subtraction would cancel most of the full Gram and lose digits).
    #[inline(always)]
    fn build_gram<A: MulAdd>(&mut self, hidden_count: usize) {
        let tri = off(self.m);
        let markers = self.blocks.len() / tri;
        let downdate = hidden_count * 2 <= markers;
        if downdate {
            self.gram.copy_from_slice(&self.gram_full);
        } else {
            self.gram.fill(0.0);
        }
        for (block, &gone) in self.blocks.chunks_exact(tri).zip(&self.hidden) {
            if downdate && gone {
                add_into::<A>(&mut self.gram, block, -1.0);
            } else if !downdate && !gone {
                add_into::<A>(&mut self.gram, block, 1.0);
            }
        }
    }

    /// The priors' matrix, both toward a prior `μ` (the last good components, added to the
    /// right-hand side per frame by [`MaskedSolver::solve`]): the model's, `σ² I`, and when
    /// the frame is ill-conditioned a ridge `λD` with `D = diag(MᵀM)`, `λ = ridge`:
    /// `(G + σ² I + λD) u = b + (σ² I + λD) μ`, so `u = μ + (G + σ² I + λD)⁻¹ (b − Gμ)`: what
    /// the data do not determine stays at `μ`. Positive definite whatever is hidden once either
    /// prior is there (`σ² > 0` or `λ > 0`, `D > 0`).
    #[inline(always)]
    fn add_priors<A: MulAdd>(&mut self, ridge: f64) {
        let m = self.m;
        unpack(&self.gram, &mut self.factor, m);
        for k in 0..m {
            self.factor[k * m + k] += self.residual_var + ridge * self.gram_full[off(k) + k];
        }
        let ok = cholesky::<A>(&mut self.factor, &mut self.pivots, m);
        debug_assert!(
            ok,
            "G + σ²I + λD is positive definite when a prior is there"
        );
    }
}

/// `g += r rᵀ` on a packed lower triangle.
fn add_outer(g: &mut [f64], r: &[f64]) {
    for (i, &ri) in r.iter().enumerate() {
        for (gij, rj) in g[off(i)..off(i) + i + 1].iter_mut().zip(r) {
            *gij += ri * rj;
        }
    }
}

/// `g += sign · block`, element-wise.
#[inline(always)]
fn add_into<A: MulAdd>(g: &mut [f64], block: &[f64], sign: f64) {
    for (gi, bi) in g.iter_mut().zip(block) {
        *gi = A::mul_add64(sign, *bi, *gi);
    }
}

/// The packed lower triangle `g` into the upper triangle of the m x m row-major `square`
/// (the lower part is not read).
#[inline(always)]
fn unpack(g: &[f64], square: &mut [f64], m: usize) {
    for k in 0..m {
        for (i, &v) in g[off(k)..off(k) + k + 1].iter().enumerate() {
            square[i * m + k] = v;
        }
    }
}

/// In-place Cholesky `A = UᵀU` of the upper triangle of the m x m row-major `a`, right-looking
/// (each step scales a row and subtracts its outer product from the rows below, loops the
/// compiler vectorises); `pivots[j] = U_jj²`. Returns false at the first non-positive pivot.
#[inline(always)]
fn cholesky<A: MulAdd>(a: &mut [f64], pivots: &mut [f64], m: usize) -> bool {
    for j in 0..m {
        let (head, below) = a.split_at_mut((j + 1) * m);
        let row_j = &mut head[j * m..];
        let d = row_j[j];
        if d.is_nan() || d <= 0.0 {
            return false;
        }
        pivots[j] = d;
        let ujj = d.sqrt();
        row_j[j] = ujj;
        let inv = 1.0 / ujj;
        for v in &mut row_j[j + 1..] {
            *v *= inv;
        }
        let row_j = &head[j * m..];
        for (r, row_i) in below.chunks_exact_mut(m).enumerate() {
            let i = j + 1 + r;
            let f = -row_j[i];
            for (x, &u) in row_i[i..].iter_mut().zip(&row_j[i..]) {
                *x = A::mul_add64(f, u, *x);
            }
        }
    }
    true
}

/// Solves `UᵀU x = b` with the factor `u` from [`cholesky`] (its upper triangle), its
/// transpose `ut` (lower triangle) and the reciprocals of its diagonal: forward with the rows
/// of `U`, backward with the rows of `Uᵀ`, each step a scaled row subtracted from the rest.
#[inline(always)]
fn solve_factored<A: MulAdd>(u: &[f64], ut: &[f64], inv_diag: &[f64], b: &[f64], x: &mut [f64]) {
    let m = b.len();
    x.copy_from_slice(b);
    for k in 0..m {
        x[k] *= inv_diag[k];
        let f = -x[k];
        let row = &u[k * m + k + 1..(k + 1) * m];
        for (xi, &v) in x[k + 1..].iter_mut().zip(row) {
            *xi = A::mul_add64(f, v, *xi);
        }
    }
    for k in (0..m).rev() {
        x[k] *= inv_diag[k];
        let f = -x[k];
        let row = &ut[k * m..k * m + k];
        for (xi, &v) in x[..k].iter_mut().zip(row) {
            *xi = A::mul_add64(f, v, *xi);
        }
    }
}

#[cfg(test)]
mod tests;
