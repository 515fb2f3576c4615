//! Training: whitening + FastICA restarts + the sign/order convention, in one call.
//!
//! ```
//! use ica_core::fit::{mixture, FastIcaParams, FitData};
//! let mix = mixture::face_like(2000, 30, 4, 0.2, 1);
//! let data = FitData::new(&mix.samples, mix.channels).expect("whole frames");
//! let out = FastIcaParams::default().n_components(4).fit(&data).expect("fit");
//! assert_eq!(out.mixing.shape(), (30, 4));
//! assert!(out.report.restarts[out.report.best_restart].solution_converged());
//! ```
//!
//! On long takes (at least twice [`crate::fastica::EXPLORE_FRAMES`] used frames, more than one
//! restart) the restarts run on an evenly strided subsample and only the winner is refined on all
//! frames; the winner's [`crate::RestartReport::refinement`] says how that went.
//!
//! # Hours of takes: the streaming fit
//! [`FastIcaParams::fit`] needs every frame in memory. [`FastIcaParams::fit_stream`] gives the
//! same output from frames read in passes (a [`ChunkSource`]), with the whitened frames kept in
//! a [`WhitenedStore`] between passes: memory is bounded by a chunk, the covariance and the
//! restarts' subsample, and the cost is linear in frames. [`StreamFit`] is the same fit as a
//! sans-IO state machine, for drivers that fold chunks on several threads:
//!
//! | Pass | Reads | Kernel (map, then `merge` in chunk order) | Memory per partial |
//! |---|---|---|---|
//! | statistics | raw frames | [`crate::whiten::Moments`] | `channels²` f64 + 128 frames |
//! | whitening | raw frames | [`crate::whiten::Whitener::whiten_into`], then [`crate::fastica::Subsample::push`] in frame order | one chunk out |
//! | update (per iteration) | whitened | [`crate::fastica::UpdateAccumulator`] | `m²` f64 + 1024 frames |
//! | sources (once) | whitened | [`crate::fastica::SourceMoments`] | `4 m` f64 + 1024 frames |
//!
//! The restarts run in memory on the subsample between the whitening pass and the first
//! update; a short take is fitted in memory from the subsample (all of its frames). The
//! streaming output has no `sources` and no `used_frames` list (see [`FitOutput`]).
//!
//! The model is `x ≈ mean + M u` with `M = P A` (paper eq. 2) in the original channel space and
//! `u = W (x - mean)` with `W` the whitening followed by the ICA rotation.
//!
//! # Sign and order convention
//! ICA leaves each component's sign and the components' order free. Here components are ordered
//! by the marker-space variance they explain, `|M_i|^2` (the squared norm of mixing column `i`, as
//! every `u_i` has unit variance), largest first. Each is signed so that its skewness over the
//! training frames is positive; when the skewness is not distinguishable from zero (below
//! [`SKEW_SIGNIFICANT`] standard errors, `sqrt(6/T)`), the largest-magnitude loading of its mixing
//! column is made positive instead.

mod amari;
mod assemble;
mod params;
mod source;
mod streamed;

pub use crate::input::Pass;
pub use crate::input::{FitData, FitError};
pub use crate::mixture;
pub use amari::amari_index;
pub use params::{FastIcaParams, DEFAULT_MAX_ITER, DEFAULT_RESTARTS, DEFAULT_SEED, DEFAULT_TOL};
pub use source::{ChunkSource, MemorySource, MemoryStore, StreamError, WhitenedStore};
pub use streamed::StreamFit;

pub use crate::fastica::{Algorithm, Contrast};
pub use crate::whiten::Components;

use nalgebra::DMatrix;

use crate::fastica::{self, Settings};
use crate::whiten::{self, Whitener};
use crate::TrainReport;
use assemble::Solved;

/// Skewness below this many standard errors counts as zero for the sign convention.
pub const SKEW_SIGNIFICANT: f64 = 3.0;

/// A trained decomposition: `x ≈ mean + mixing · u`, `u = unmixing · (x - mean)`.
#[derive(Debug, Clone)]
pub struct FitOutput {
    /// Per-channel mean of the used frames (`channels` long).
    pub mean: Vec<f64>,
    /// `M = P A`, `channels x m`: column `i` is component `i`'s displacement per unit of `u_i`.
    /// Rows of dead channels are zero.
    pub mixing: DMatrix<f64>,
    /// `W`, `m x channels`: whitening then rotation. Columns of dead channels are zero, so a dead
    /// channel's value never reaches `u`. `unmixing · mixing = I`.
    pub unmixing: DMatrix<f64>,
    /// Marker-space variance each component explains, `|M_i|^2`, in component order (decreasing).
    pub component_variance: Vec<f64>,
    /// The components of the used frames, `frames_used x m` (row `r` is frame `used_frames[r]`),
    /// unit variance; `None` if [`FastIcaParams::keep_sources`] was off, and always `None` from
    /// the streaming fit ([`FastIcaParams::fit_stream`], [`StreamFit`]), which keeps no
    /// per-frame state.
    pub sources: Option<DMatrix<f64>>,
    /// Indices of the frames used for training, ascending. Empty from the streaming fit: its
    /// count is `report.frames_used`, and a frame was used exactly when
    /// [`crate::whiten::Whitener::frame_is_used`] says so (no missing sample except on channels
    /// missing in every frame).
    pub used_frames: Vec<usize>,
    /// What training did.
    pub report: TrainReport,
}

impl FastIcaParams {
    /// Fits the decomposition to `data`.
    ///
    /// Deterministic: the same data and parameters give bit-identical output.
    ///
    /// # Errors
    /// A bad parameter, non-finite present samples, too few complete frames, all channels dead,
    /// or `m` above the data's rank: see [`FitError`].
    pub fn fit<T: Copy + Into<f64>>(&self, data: &FitData<'_, T>) -> Result<FitOutput, FitError> {
        self.check()?;
        let (wh, whitened, used_frames) = whiten::whiten_parts(data, self.components)?;
        let run = fastica::run(&whitened, self.settings());
        let (mut out, sources) = self.finish_in_memory(&wh, run);
        out.sources = self.keep_sources.then_some(sources);
        out.used_frames = used_frames;
        Ok(out)
    }

    /// The iteration settings of these parameters.
    pub(crate) fn settings(&self) -> Settings {
        Settings {
            contrast: self.contrast,
            algorithm: self.algorithm,
            tol: self.tol,
            max_iter: self.max_iter,
            seed: self.seed,
            restarts: self.restarts,
        }
    }

    /// The output of a FastICA run over every used frame held in memory, and its sources in
    /// canonical order and sign (`frames x m`).
    pub(crate) fn finish_in_memory(
        &self,
        wh: &Whitener,
        run: fastica::IcaRun,
    ) -> (FitOutput, DMatrix<f64>) {
        let frames = run.sources.nrows();
        let skew: Vec<f64> = run
            .sources
            .as_slice()
            .chunks_exact(frames.max(1))
            .map(assemble::skewness)
            .collect();
        let solved = Solved {
            w: run.w,
            restarts: run.restarts,
            best: run.best,
            restart_w: run.restart_w,
        };
        let (out, canon) = assemble::output(self, wh, solved, &skew, frames);
        let sources = canon.sources(&run.sources);
        (out, sources)
    }
}
