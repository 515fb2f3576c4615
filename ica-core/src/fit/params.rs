//! FastICA hyperparameters: a linfa-style consuming builder checked once at `fit`.

use super::FitError;
use crate::fastica::{Algorithm, Contrast};
use crate::whiten::Components;

/// Default convergence tolerance on `max |1 - |diag(W_new W_old^T)||`.
pub const DEFAULT_TOL: f64 = 1e-4;
/// Default iteration cap per restart. scikit-learn's 200 is too few for face data at m = 20;
/// converged restarts stop long before this.
pub const DEFAULT_MAX_ITER: usize = 1000;
/// Default number of seeded restarts.
pub const DEFAULT_RESTARTS: usize = 4;
/// Default base seed.
pub const DEFAULT_SEED: u64 = 0;

/// Hyperparameters of a fit: whitening size, contrast, update rule, stopping rule, seeding.
///
/// ```
/// use ica_core::fit::{Contrast, FastIcaParams};
/// let params = FastIcaParams::default()
///     .n_components(10)
///     .contrast(Contrast::LogCosh)
///     .max_iter(500)
///     .tol(1e-5)
///     .seed(7)
///     .restarts(2);
/// assert_eq!(params.get_max_iter(), 500);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct FastIcaParams {
    pub(crate) components: Components,
    pub(crate) contrast: Contrast,
    pub(crate) algorithm: Algorithm,
    pub(crate) tol: f64,
    pub(crate) max_iter: usize,
    pub(crate) seed: u64,
    pub(crate) restarts: usize,
    pub(crate) keep_sources: bool,
}

impl Default for FastIcaParams {
    /// Variance target 0.97, logcosh, symmetric, tol 1e-4, 1000 iterations, seed 0, 4 restarts,
    /// training sources kept.
    fn default() -> Self {
        Self {
            components: Components::default(),
            contrast: Contrast::default(),
            algorithm: Algorithm::default(),
            tol: DEFAULT_TOL,
            max_iter: DEFAULT_MAX_ITER,
            seed: DEFAULT_SEED,
            restarts: DEFAULT_RESTARTS,
            keep_sources: true,
        }
    }
}

impl FastIcaParams {
    /// How many components to keep (variance target or fixed count).
    pub fn components(mut self, components: Components) -> Self {
        self.components = components;
        self
    }

    /// Keep exactly `m` components (shorthand for `Components::Fixed(m)`).
    pub fn n_components(self, m: usize) -> Self {
        self.components(Components::Fixed(m))
    }

    /// Keep the fewest components explaining `target` of the variance (0.90 to 0.999).
    pub fn variance_target(self, target: f64) -> Self {
        self.components(Components::VarianceTarget(target))
    }

    /// Contrast function.
    pub fn contrast(mut self, contrast: Contrast) -> Self {
        self.contrast = contrast;
        self
    }

    /// Update rule.
    pub fn algorithm(mut self, algorithm: Algorithm) -> Self {
        self.algorithm = algorithm;
        self
    }

    /// Convergence tolerance on `max |1 - |diag(W_new W_old^T)||`.
    pub fn tol(mut self, tol: f64) -> Self {
        self.tol = tol;
        self
    }

    /// Iteration cap per restart.
    pub fn max_iter(mut self, max_iter: usize) -> Self {
        self.max_iter = max_iter;
        self
    }

    /// Base seed; restart `k` uses [`crate::fastica::restart_seed`]`(seed, k)`.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Number of restarts (at least 1).
    pub fn restarts(mut self, restarts: usize) -> Self {
        self.restarts = restarts;
        self
    }

    /// Whether [`super::FitOutput::sources`] holds the training frames' components.
    pub fn keep_sources(mut self, keep: bool) -> Self {
        self.keep_sources = keep;
        self
    }

    /// The component request.
    pub fn get_components(&self) -> Components {
        self.components
    }

    /// Restarts.
    pub fn get_restarts(&self) -> usize {
        self.restarts
    }

    /// The iteration cap.
    pub fn get_max_iter(&self) -> usize {
        self.max_iter
    }

    /// Checks every parameter that can be checked without data.
    ///
    /// # Errors
    /// [`FitError::VarianceTarget`], [`FitError::ZeroComponents`], [`FitError::Tolerance`],
    /// [`FitError::ZeroIterations`] or [`FitError::ZeroRestarts`].
    pub fn check(&self) -> Result<(), FitError> {
        self.components.check()?;
        if !(self.tol.is_finite() && self.tol > 0.0) {
            return Err(FitError::Tolerance { tol: self.tol });
        }
        if self.max_iter == 0 {
            return Err(FitError::ZeroIterations);
        }
        if self.restarts == 0 {
            return Err(FitError::ZeroRestarts);
        }
        Ok(())
    }
}
