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
//! **Layout and instructions.** Where the CPU has AVX2 and FMA (detected once, at
//! [`Projector::new`], through pulp's safe dispatch) the kernels are written with 8-lane
//! vectors and read one matrix for both passes: `W = M⁺`, so with the thin QR `M = QR`,
//! `u = R⁻¹(Qᵀc)` and `x' = mean + Q(Ru')`, with `Q`'s columns stored block-interleaved in
//! groups as the loops read them (see `avx2`): 52 KB at m = 20 and 109 markers became 26 KB,
//! inside a core's L1 cache. Elsewhere the portable kernels run, loops over contiguous memory
//! that the compiler vectorises for SSE: `W·c` over `Wᵀ` stored as n rows of m values
//! zero-padded to a multiple of 8 (up to 32), `u += c_j · Wᵀ[j]` into two fixed-size
//! accumulators, and `M·u` as column axpys, four columns per pass over the output. Models of
//! more than 32 components use m rows of n and dot products.
//!
//! **Missing markers** (a `missing` mask, or any non-finite coordinate) are handled by
//! least squares on the observed rows with the model's own prior: the posterior mean of a
//! probabilistic PCA, see [`MIN_OBSERVABILITY`] for the method and the [`FrameStatus`] flags.
//! The factorisation of that system depends only on which markers are hidden; it is kept
//! while the same markers stay hidden (an occlusion lasts many frames), so such a frame costs
//! two triangular solves and the two passes over `Q`.

#[cfg(target_arch = "x86_64")]
mod avx2;
mod kernels;
mod masked;
mod status;
mod tasks;

pub use masked::MIN_OBSERVABILITY;
pub use status::FrameStatus;

pub use crate::frame::FrameError;

use crate::frame::FrameEdit;
use crate::model::IcaModel;
use kernels::Simd;
use masked::MaskedSolver;
use tasks::{Axpy, CenterVisible, MaskedSolve, NormalRhs};

/// Per-frame projector built from an [`IcaModel`]; owns every buffer it needs.
#[derive(Debug, Clone)]
pub struct Projector {
    channels: usize,
    components: usize,
    /// `W` as m rows of `row_stride` (zero padded) when the CPU has AVX2 + FMA or `m` is
    /// over 32, else as a `Wᵀ` panel (n rows of `panel_width`, zero padded).
    unmixing: Vec<f32>,
    /// A multiple of 8 up to 32; 0 for the row layout.
    panel_width: usize,
    /// Row length of the row layout: n, rounded up to whole vectors for the AVX2 kernel.
    row_stride: usize,
    /// `M` column-major: column k is `mixing[k*n..(k+1)*n]`.
    mixing: Vec<f32>,
    mean: Vec<f32>,
    centered: Vec<f32>,
    last_u: Vec<f32>,
    /// Scratch: the hidden markers' indices in a masked frame.
    gone: Vec<usize>,
    solver: MaskedSolver,
    /// The instruction set the kernels run with.
    simd: Simd,
    /// The AVX2 + FMA kernels and the matrices in their layout, where the CPU has them.
    #[cfg(target_arch = "x86_64")]
    avx2: Option<(pulp::x86::V3, avx2::Layout)>,
}

impl Projector {
    /// Copies the model's matrices to f32 in the frame-path layout.
    pub fn new(model: &IcaModel) -> Projector {
        let (n, m) = model.mixing().shape();
        let w = model.unmixing();
        let simd = Simd::detect();
        let (panel_width, row_stride) = (kernels::panel_width(m), n);
        let unmixing = if panel_width > 0 {
            let wt = |j: usize, k: usize| if k < m { w[(k, j)] as f32 } else { 0.0 };
            (0..n)
                .flat_map(|j| (0..panel_width).map(move |k| wt(j, k)))
                .collect()
        } else {
            let wr = move |k: usize, j: usize| if j < n { w[(k, j)] as f32 } else { 0.0 };
            (0..m)
                .flat_map(|k| (0..row_stride).map(move |j| wr(k, j)))
                .collect()
        };
        // nalgebra is column-major already.
        let mixing = model.mixing().iter().map(|&v| v as f32).collect();
        let rows: Vec<f64> = (0..n)
            .flat_map(|j| (0..m).map(move |k| model.mixing()[(j, k)]))
            .collect();
        let mean: Vec<f32> = model.mean().iter().map(|&v| v as f32).collect();
        // The AVX2 layout holds small m x m factors on the stack: up to 32 components.
        #[cfg(target_arch = "x86_64")]
        let avx2 = pulp::x86::V3::try_new()
            .filter(|_| m <= 32)
            .and_then(|v3| Some((v3, avx2::Layout::new(model.mixing(), &mean)?)));
        Projector {
            channels: n,
            components: m,
            unmixing,
            panel_width,
            row_stride,
            mixing,
            mean,
            centered: vec![0.0; row_stride],
            last_u: vec![0.0; m],
            gone: vec![0; n / 3],
            solver: MaskedSolver::new(&rows, m, model.residual_variance()),
            simd,
            #[cfg(target_arch = "x86_64")]
            avx2,
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
        Ok(self.project_gappy(x, missing, u))
    }

    /// Resynthesis `out = mean + M u`.
    ///
    /// # Errors
    /// [`FrameError::Length`] when `u` or `out` has the wrong length.
    pub fn resynth_into(&self, u: &[f32], out: &mut [f32]) -> Result<(), FrameError> {
        check_len("components", self.components, u.len())?;
        check_len("output", self.channels, out.len())?;
        self.resynth(u, out);
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
        let column = &self.mixing[k * self.channels..(k + 1) * self.channels];
        self.simd.run(Axpy {
            a: value,
            x: column,
            y: out,
        });
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
        check_len("frame", self.channels, x.len())?;
        check_len("components", self.components, out_u.len())?;
        if let Some(mask) = missing {
            check_len("missing mask", self.markers(), mask.len())?;
        }
        let any_flag = missing.is_some_and(|mask| mask.iter().any(|&b| b));
        if !any_flag {
            self.project_full(x, out_u);
            // A non-finite coordinate makes every component non-finite: the gappy path.
            if out_u.iter().all(|v| v.is_finite()) {
                self.last_u.copy_from_slice(out_u);
                edit.apply_sized(out_u);
                self.resynth(out_u, out_x);
                return Ok(FrameStatus {
                    observability: 1.0,
                    ..FrameStatus::default()
                });
            }
        }
        let status = self.project_gappy(x, missing, out_u);
        edit.apply(out_u)?;
        self.resynth_into(out_u, out_x)?;
        Ok(status)
    }

    /// `u = W (x − mean)`; the panel kernels fuse the subtraction into the product.
    fn project_full(&mut self, x: &[f32], u: &mut [f32]) {
        #[cfg(target_arch = "x86_64")]
        if let Some((v3, layout)) = &mut self.avx2 {
            let op = avx2::Project {
                v3: *v3,
                layout,
                x,
                u,
            };
            return pulp::Simd::vectorize(*v3, op);
        }
        if self.panel_width > 0 {
            self.simd
                .panel_gemv(&self.unmixing, self.panel_width, x, &self.mean, u);
        } else {
            self.simd.rows_gemv(
                &self.unmixing,
                self.row_stride,
                x,
                &self.mean,
                &mut self.centered,
                u,
            );
        }
    }

    /// `out = mean + M u`.
    fn resynth(&self, u: &[f32], out: &mut [f32]) {
        #[cfg(target_arch = "x86_64")]
        if let Some((v3, layout)) = &self.avx2 {
            let op = avx2::Resynth {
                v3: *v3,
                layout,
                u,
                out,
            };
            return pulp::Simd::vectorize(*v3, op);
        }
        self.simd.resynth(&self.mixing, &self.mean, u, out);
    }

    /// The solver's right-hand side `Mᵀc` from the centred frame (missing channels zeroed):
    /// `Rᵀ(Qᵀc)` through the AVX2 layout's `Q`, else one dot product per column of `M`.
    fn normal_rhs(&mut self) {
        let n = self.channels;
        #[cfg(target_arch = "x86_64")]
        if let Some((v3, layout)) = &mut self.avx2 {
            let op = avx2::Normal {
                v3: *v3,
                layout,
                c: &self.centered[..n],
                rhs: self.solver.rhs_mut(),
            };
            return pulp::Simd::vectorize(*v3, op);
        }
        self.simd.run(NormalRhs {
            mixing: &self.mixing,
            centered: &self.centered[..n],
            rhs: self.solver.rhs_mut(),
        });
    }

    /// The slow path: centre the frame with the hidden markers zeroed, then least squares or
    /// hold.
    fn project_gappy(&mut self, x: &[f32], missing: Option<&[bool]>, u: &mut [f32]) -> FrameStatus {
        let n = self.channels;
        let missing_markers = self.simd.run(CenterVisible {
            x,
            mean: &self.mean,
            missing,
            centered: &mut self.centered[..n],
            hidden: self.solver.hidden_mut(),
            gone: &mut self.gone,
        });
        let mut status = FrameStatus {
            masked: true,
            missing_markers,
            ..FrameStatus::default()
        };
        if n - 3 * missing_markers < self.components {
            u.copy_from_slice(&self.last_u);
            status.held = true;
            return status;
        }
        self.normal_rhs();
        let solve = self.simd.run(MaskedSolve {
            solver: &mut self.solver,
            hidden_count: missing_markers,
            prior: &self.last_u,
            u,
        });
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

#[cfg(test)]
mod tests;
