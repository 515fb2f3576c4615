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
    factor: Vec<f64>,
    pivots: Vec<f64>,
    rhs: Vec<f64>,
    sol: Vec<f64>,
    /// Residual variance per channel: the prior's weight (0: plain least squares).
    residual_var: f64,
}

/// What a masked solve found.
#[derive(Debug, Clone, Copy)]
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
            add_into(&mut gram_full, block, 1.0);
        }
        let mut s = MaskedSolver {
            m,
            blocks,
            gram_full,
            pivots_full: vec![0.0; m],
            gram: vec![0.0; tri],
            factor: vec![0.0; tri],
            pivots: vec![0.0; m],
            rhs: vec![0.0; m],
            sol: vec![0.0; m],
            residual_var: if residual_var.is_finite() {
                residual_var.max(0.0)
            } else {
                0.0
            },
        };
        s.factor.copy_from_slice(&s.gram_full);
        let ok = cholesky(&mut s.factor, &mut s.pivots_full, m);
        assert!(
            ok,
            "a full-rank mixing matrix has a positive definite Gram matrix"
        );
        s
    }

    /// Solves for `u` given `rhs` = `Mᵀc` for the centred frame `c` with missing channels
    /// zeroed (so it equals `M_oᵀ c_o`), the per-marker `hidden` flags (`hidden_count` of
    /// them set), and the `prior` used when the frame is ill-conditioned.
    pub(crate) fn solve(
        &mut self,
        rhs: impl Iterator<Item = f64>,
        hidden: impl Iterator<Item = bool> + Clone,
        hidden_count: usize,
        prior: &[f32],
        u: &mut [f32],
    ) -> Solve {
        let m = self.m;
        for (r, v) in self.rhs.iter_mut().zip(rhs) {
            *r = v;
        }
        self.build_gram(hidden, hidden_count);
        self.factor.copy_from_slice(&self.gram);
        // Observability is measured on the data alone; the solve then adds the priors.
        let ok = cholesky(&mut self.factor, &mut self.pivots, m);
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
            self.add_priors(prior, ridge);
        }
        solve_factored(&self.factor, &self.rhs, &mut self.sol, m);
        for (ui, s) in u.iter_mut().zip(&self.sol) {
            *ui = *s as f32;
        }
        Solve {
            observability: observability.max(0.0),
            ill_conditioned,
        }
    }

    /// `M_oᵀ M_o`, by subtracting the hidden markers' blocks from the full Gram when they are
    /// the minority (cheap for a few occluded markers) and by summing the observed blocks
    /// otherwise (the subtraction would cancel most of the full Gram and lose digits).
    fn build_gram(&mut self, hidden: impl Iterator<Item = bool> + Clone, hidden_count: usize) {
        let tri = off(self.m);
        let markers = self.blocks.len() / tri;
        let downdate = hidden_count * 2 <= markers;
        if downdate {
            self.gram.copy_from_slice(&self.gram_full);
        } else {
            self.gram.fill(0.0);
        }
        for (block, gone) in self.blocks.chunks_exact(tri).zip(hidden) {
            if downdate && gone {
                add_into(&mut self.gram, block, -1.0);
            } else if !downdate && !gone {
                add_into(&mut self.gram, block, 1.0);
            }
        }
    }

    /// The priors, both toward `prior` (`μ`): the model's, `σ² I`, and when the frame is
    /// ill-conditioned a ridge `λD` with `D = diag(MᵀM)`, `λ = ridge`:
    /// `(G + σ² I + λD) u = b + (σ² I + λD) μ`, so `u = μ + (G + σ² I + λD)⁻¹ (b − Gμ)`: what
    /// the data do not determine stays at `μ`. Positive definite whatever is hidden once either
    /// prior is there (`σ² > 0` or `λ > 0`, `D > 0`).
    fn add_priors(&mut self, prior: &[f32], ridge: f64) {
        self.factor.copy_from_slice(&self.gram);
        for (k, (r, &p)) in self.rhs.iter_mut().zip(prior).enumerate() {
            let kk = off(k) + k;
            let d = self.residual_var + ridge * self.gram_full[kk];
            self.factor[kk] += d;
            *r += d * f64::from(p);
        }
        let ok = cholesky(&mut self.factor, &mut self.pivots, self.m);
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
fn add_into(g: &mut [f64], block: &[f64], sign: f64) {
    for (gi, bi) in g.iter_mut().zip(block) {
        *gi += sign * bi;
    }
}

/// In-place Cholesky `A = L Lᵀ` of a packed lower triangle; `pivots[j] = L_jj²`. Returns
/// false at the first non-positive pivot.
fn cholesky(a: &mut [f64], pivots: &mut [f64], m: usize) -> bool {
    for j in 0..m {
        let (head, below) = a.split_at_mut(off(j + 1));
        let row_j = &mut head[off(j)..];
        let d = row_j[j] - row_j[..j].iter().map(|v| v * v).sum::<f64>();
        if d.is_nan() || d <= 0.0 {
            return false;
        }
        pivots[j] = d;
        let ljj = d.sqrt();
        row_j[j] = ljj;
        let row_j = &head[off(j)..];
        for i in (j + 1)..m {
            let row_i = &mut below[off(i) - off(j + 1)..off(i + 1) - off(j + 1)];
            let s: f64 = row_i[..j].iter().zip(&row_j[..j]).map(|(x, y)| x * y).sum();
            row_i[j] = (row_i[j] - s) / ljj;
        }
    }
    true
}

/// Solves `L Lᵀ x = b` with the packed factor from [`cholesky`].
fn solve_factored(l: &[f64], b: &[f64], x: &mut [f64], m: usize) {
    for i in 0..m {
        let s: f64 = l[off(i)..off(i) + i]
            .iter()
            .zip(&x[..i])
            .map(|(a, y)| a * y)
            .sum();
        x[i] = (b[i] - s) / l[off(i) + i];
    }
    for i in (0..m).rev() {
        let s: f64 = ((i + 1)..m).map(|k| l[off(k) + i] * x[k]).sum();
        x[i] = (x[i] - s) / l[off(i) + i];
    }
}

#[cfg(test)]
mod tests;
