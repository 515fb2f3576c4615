//! The per-frame path: project a marker frame to components, edit, resynthesise.
//!
//! `u = W (x − mean)`, edit `u → u'`, `x' = mean + M u'` (paper section 5), in f32 with every
//! buffer allocated by [`Projector::new`]; a frame call allocates nothing (held by
//! `tests/it/alloc.rs`).
//!
//! **Precision.** `W`, `M` and the mean are f32 copies of the model's f64 matrices. A frame
//! round trip (project, resynthesise) differs from the f64 computation by about
//! `ε₃₂ · (|x| + cond(M)·|x − mean|)`, ~1e-4 mm for a face in millimetres a metre from the
//! origin with a well-conditioned model: the f32 spacing of the raw coordinates dominates.
//!
//! **Layout.** Both products are loops over contiguous memory that the compiler vectorises
//! without `unsafe` or target-specific code. `W·c` runs over `Wᵀ` stored as n rows of m
//! values zero-padded to a fixed width (a multiple of 4 up to 32, one SSE register per 4): `u += c_j · Wᵀ[j]` with `u` held in
//! a fixed-size accumulator, i.e. in registers (measured ~1.7x faster than m dot products,
//! whose float reductions LLVM vectorises only two lanes wide). Models with more than 32
//! components fall back to m rows of n and dot products. `M` is stored column-major, so
//! `M·u` is a sum of column axpys, four columns per pass over the output.
//!
//! **Missing markers** (a `missing` mask, or any non-finite coordinate) are handled by
//! least squares on the observed rows with the model's own prior: the posterior mean of a
//! probabilistic PCA, see [`MIN_OBSERVABILITY`] for the method and the [`FrameStatus`] flags.

mod kernels;
mod masked;

pub use masked::MIN_OBSERVABILITY;

pub use crate::frame::FrameError;

use crate::frame::FrameEdit;
use crate::model::IcaModel;
use kernels::{axpy, axpy4, axpy4_onto, panel_gemv, sub_into, PANEL_WIDTHS};
use masked::MaskedSolver;

/// What happened to one frame's projection.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FrameStatus {
    /// Some markers were missing (masked or non-finite) and were solved around.
    pub masked: bool,
    /// Markers missing in this frame.
    pub missing_markers: usize,
    /// The observed markers barely determine some component (observability below
    /// [`MIN_OBSERVABILITY`]): the solve was regularised toward the last good components.
    pub ill_conditioned: bool,
    /// Fewer observed channels than components: `u` was held at the last good value (or 0,
    /// the mean pose, before any).
    pub held: bool,
    /// Smallest share of a component's footprint still observed, in `[0, 1]`: 1 for a full
    /// frame, 0 for a held one.
    pub observability: f32,
}

/// Per-frame projector built from an [`IcaModel`]; owns every buffer it needs.
#[derive(Debug, Clone)]
pub struct Projector {
    channels: usize,
    components: usize,
    /// `W` as `Wᵀ` panel (n rows of `panel_width`, zero padded) when `m` fits a panel,
    /// else m rows of n.
    unmixing: Vec<f32>,
    /// A multiple of 4 up to 32; 0 for the row layout.
    panel_width: usize,
    /// `M` column-major: column k is `mixing[k*n..(k+1)*n]`.
    mixing: Vec<f32>,
    mean: Vec<f32>,
    centered: Vec<f32>,
    observed: Vec<bool>,
    last_u: Vec<f32>,
    solver: MaskedSolver,
}

impl Projector {
    /// Copies the model's matrices to f32 in the frame-path layout.
    pub fn new(model: &IcaModel) -> Projector {
        let (n, m) = model.mixing().shape();
        let w = model.unmixing();
        let panel_width = PANEL_WIDTHS.iter().copied().find(|&k| k >= m).unwrap_or(0);
        let unmixing = if panel_width > 0 {
            let wt = |j: usize, k: usize| if k < m { w[(k, j)] as f32 } else { 0.0 };
            (0..n)
                .flat_map(|j| (0..panel_width).map(move |k| wt(j, k)))
                .collect()
        } else {
            (0..m)
                .flat_map(|k| (0..n).map(move |j| w[(k, j)] as f32))
                .collect()
        };
        // nalgebra is column-major already.
        let mixing = model.mixing().iter().map(|&v| v as f32).collect();
        let rows: Vec<f64> = (0..n)
            .flat_map(|j| (0..m).map(move |k| model.mixing()[(j, k)]))
            .collect();
        Projector {
            channels: n,
            components: m,
            unmixing,
            panel_width,
            mixing,
            mean: model.mean().iter().map(|&v| v as f32).collect(),
            centered: vec![0.0; n],
            observed: vec![true; n],
            last_u: vec![0.0; m],
            solver: MaskedSolver::new(&rows, m, model.residual_variance()),
        }
    }

    /// Channels per frame (markers x 3).
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// Markers per frame.
    pub fn markers(&self) -> usize {
        self.channels / 3
    }

    /// Components per frame.
    pub fn components(&self) -> usize {
        self.components
    }

    /// Forgets the last good components, so a held frame falls back to the mean pose.
    pub fn reset(&mut self) {
        self.last_u.fill(0.0);
    }

    /// Full-frame projection `u = W (x − mean)`. No missing-marker handling: use
    /// [`Projector::project_masked_into`] when a frame may have gaps.
    ///
    /// # Errors
    /// [`FrameError::Length`] when `x` or `u` has the wrong length.
    pub fn project_into(&mut self, x: &[f32], u: &mut [f32]) -> Result<(), FrameError> {
        check_len("frame", self.channels, x.len())?;
        check_len("components", self.components, u.len())?;
        self.project_full(x, u);
        self.last_u.copy_from_slice(u);
        Ok(())
    }

    /// Projection that tolerates missing markers: markers flagged in `missing` (one flag per
    /// marker) or with any non-finite coordinate are left out and `u` is the least-squares
    /// fit to the rest. See [`FrameStatus`] for the flags.
    ///
    /// # Errors
    /// [`FrameError::Length`] when `x`, `missing` or `u` has the wrong length.
    pub fn project_masked_into(
        &mut self,
        x: &[f32],
        missing: Option<&[bool]>,
        u: &mut [f32],
    ) -> Result<FrameStatus, FrameError> {
        check_len("frame", self.channels, x.len())?;
        check_len("components", self.components, u.len())?;
        if let Some(mask) = missing {
            check_len("missing mask", self.markers(), mask.len())?;
        }
        let any_flag = missing.is_some_and(|mask| mask.iter().any(|&b| b));
        // A non-finite coordinate makes every u_k non-finite (NaN·w = ±inf·0 = NaN, ±inf·w =
        // ±inf, and sums keep them), so checking the m outputs replaces a pass over the frame.
        if !any_flag {
            self.project_full(x, u);
        }
        if !any_flag && u.iter().all(|v| v.is_finite()) {
            self.last_u.copy_from_slice(u);
            return Ok(FrameStatus {
                observability: 1.0,
                ..FrameStatus::default()
            });
        }
        sub_into(x, &self.mean, &mut self.centered);
        Ok(self.project_gappy(missing, u))
    }

    /// Resynthesis `out = mean + M u`.
    ///
    /// # Errors
    /// [`FrameError::Length`] when `u` or `out` has the wrong length.
    pub fn resynth_into(&self, u: &[f32], out: &mut [f32]) -> Result<(), FrameError> {
        check_len("components", self.components, u.len())?;
        check_len("output", self.channels, out.len())?;
        let n = self.channels;
        let mut cols = self.mixing.chunks_exact(4 * n);
        let mut uk = u.chunks_exact(4);
        if self.components < 4 {
            out.copy_from_slice(&self.mean);
        }
        for (i, (block, a)) in (&mut cols).zip(&mut uk).enumerate() {
            let (c0, rest) = block.split_at(n);
            let (c1, rest) = rest.split_at(n);
            let (c2, c3) = rest.split_at(n);
            let (a, c) = ([a[0], a[1], a[2], a[3]], [c0, c1, c2, c3]);
            // The first four columns start from the mean: no separate copy pass.
            if i == 0 {
                axpy4_onto(&self.mean, a, c, out);
            } else {
                axpy4(a, c, out);
            }
        }
        for (col, &a) in cols.remainder().chunks_exact(n).zip(uk.remainder()) {
            axpy(a, col, out);
        }
        Ok(())
    }

    /// `out += value · M[:, k]`: one component's contribution, the building block of the
    /// paper's *Copy and Add* across two models (see [`crate::edit::copy_add_into`]).
    ///
    /// # Errors
    /// [`FrameError::ComponentOutOfRange`] or [`FrameError::Length`].
    pub fn add_component_into(
        &self,
        k: usize,
        value: f32,
        out: &mut [f32],
    ) -> Result<(), FrameError> {
        if k >= self.components {
            return Err(FrameError::ComponentOutOfRange {
                index: k,
                components: self.components,
            });
        }
        check_len("output", self.channels, out.len())?;
        axpy(
            value,
            &self.mixing[k * self.channels..(k + 1) * self.channels],
            out,
        );
        Ok(())
    }

    /// Project (tolerating missing markers), apply `edit`, resynthesise: `out_u` receives the
    /// edited components, `out_x` the edited frame (every marker, missing ones filled in
    /// from the model).
    ///
    /// # Errors
    /// [`FrameError::Length`] when a buffer or the edit does not match the model.
    pub fn process_into(
        &mut self,
        x: &[f32],
        missing: Option<&[bool]>,
        edit: &FrameEdit,
        out_x: &mut [f32],
        out_u: &mut [f32],
    ) -> Result<FrameStatus, FrameError> {
        check_len("edit", self.components, edit.components())?;
        check_len("output", self.channels, out_x.len())?;
        let status = self.project_masked_into(x, missing, out_u)?;
        edit.apply(out_u)?;
        self.resynth_into(out_u, out_x)?;
        Ok(status)
    }

    /// `u = W (x − mean)`; the panel kernels fuse the subtraction into the product.
    fn project_full(&mut self, x: &[f32], u: &mut [f32]) {
        let (w, mean) = (&self.unmixing, &self.mean);
        match self.panel_width {
            4 => panel_gemv::<4>(w, x, mean, u),
            8 => panel_gemv::<8>(w, x, mean, u),
            12 => panel_gemv::<12>(w, x, mean, u),
            16 => panel_gemv::<16>(w, x, mean, u),
            20 => panel_gemv::<20>(w, x, mean, u),
            24 => panel_gemv::<24>(w, x, mean, u),
            28 => panel_gemv::<28>(w, x, mean, u),
            32 => panel_gemv::<32>(w, x, mean, u),
            _ => {
                sub_into(x, mean, &mut self.centered);
                for (row, o) in w.chunks_exact(self.channels).zip(u.iter_mut()) {
                    *o = kernels::dot(row, &self.centered);
                }
            }
        }
    }

    /// The slow path: build the observed mask, then least squares or hold.
    fn project_gappy(&mut self, missing: Option<&[bool]>, u: &mut [f32]) -> FrameStatus {
        let mut missing_markers = 0;
        for (i, (obs, c)) in self
            .observed
            .chunks_exact_mut(3)
            .zip(self.centered.chunks_exact_mut(3))
            .enumerate()
        {
            let gone = missing.is_some_and(|mask| mask[i]) || !c.iter().all(|v| v.is_finite());
            obs.fill(!gone);
            if gone {
                // Zeroed so that `Mᵀ c` sums the observed rows only.
                c.fill(0.0);
                missing_markers += 1;
            }
        }
        let hidden = 3 * missing_markers;
        let mut status = FrameStatus {
            masked: true,
            missing_markers,
            ..FrameStatus::default()
        };
        if self.channels - hidden < self.components {
            u.copy_from_slice(&self.last_u);
            status.held = true;
            return status;
        }
        let n = self.channels;
        let (mixing, centered) = (&self.mixing, &self.centered);
        let rhs = mixing
            .chunks_exact(n)
            .map(|col| f64::from(kernels::dot(col, centered)));
        let hidden_markers = self.observed.iter().step_by(3).map(|&obs| !obs);
        let solve = self
            .solver
            .solve(rhs, hidden_markers, missing_markers, &self.last_u, u);
        status.observability = solve.observability as f32;
        status.ill_conditioned = solve.ill_conditioned;
        self.last_u.copy_from_slice(u);
        status
    }
}

fn check_len(what: &'static str, expected: usize, got: usize) -> Result<(), FrameError> {
    if expected == got {
        Ok(())
    } else {
        Err(FrameError::Length {
            what,
            expected,
            got,
        })
    }
}
