//! The training report: what a fit did, returned as data instead of logged.

use serde::{Deserialize, Serialize};

/// Diagnostics of one FastICA restart.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RestartReport {
    /// Seed this restart's initial unmixing matrix was drawn from.
    pub seed: u64,
    /// Iterations run.
    pub iterations: usize,
    /// Whether the update converged below the tolerance.
    pub converged: bool,
    /// The last update's change, `max |1 - |diag(W_new W_old^T)||`.
    pub last_delta: f64,
    /// Total negentropy approximation of the solution (larger is better), over `frames`.
    pub negentropy: f64,
    /// Frames the iteration ran on: on long takes the restarts explore an evenly strided
    /// subsample and only the winner is refined on every used frame (see `refinement`).
    /// 0 in reports written before this field existed.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub frames: usize,
    /// For the winning restart of a subsampled fit: the final run on all used frames, started
    /// from this restart's solution. The kept solution is this one's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refinement: Option<Refinement>,
}

/// The final FastICA run on all used frames, continuing from the best subsampled restart.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Refinement {
    /// Frames it ran on (every used frame).
    pub frames: usize,
    /// Iterations run.
    pub iterations: usize,
    /// Whether the update converged below the tolerance.
    pub converged: bool,
    /// The last update's change, `max |1 - |diag(W_new W_old^T)||`.
    pub last_delta: f64,
    /// Total negentropy approximation of the kept solution over all used frames.
    pub negentropy: f64,
}

impl RestartReport {
    /// Whether the solution this restart leads to converged: its own run and, when it was
    /// refined on all frames, the refinement too.
    pub fn solution_converged(&self) -> bool {
        self.converged && self.refinement.as_ref().is_none_or(|r| r.converged)
    }
}

/// Serde helper: a zero count is the default and is not written.
fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// What training did: data used, whitening, and every FastICA restart.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainReport {
    /// Frames offered to training.
    pub frames_total: usize,
    /// Frames used for the statistics (frames with missing samples are excluded).
    pub frames_used: usize,
    /// Channels (markers x 3).
    pub channels: usize,
    /// Channels whose variance was about zero (indices into the channel vector).
    pub dead_channels: Vec<usize>,
    /// Components kept.
    pub components: usize,
    /// Share of the total variance the kept principal components explain.
    pub variance_kept: f64,
    /// Eigenvalues of the covariance, largest first (all of them, for scree plots).
    pub eigenvalues: Vec<f64>,
    /// Contrast function used (`logcosh`, `exp`, `cube`).
    pub contrast: String,
    /// Update rule (`symmetric` or `deflation`).
    pub algorithm: String,
    /// Tolerance.
    pub tol: f64,
    /// Iteration cap per restart.
    pub max_iter: usize,
    /// Each restart, in the order run.
    pub restarts: Vec<RestartReport>,
    /// Index into `restarts` of the solution kept.
    pub best_restart: usize,
    /// Stability of each kept component across the restarts (component order): the mean over
    /// the other restarts of its best-match |correlation| with their components, in the manner
    /// of ICASSO. 1 means every restart found it; empty with a single restart or in reports
    /// written before this field existed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub stability: Vec<f64>,
}

impl TrainReport {
    /// The report of a model that was not trained on data: one frame, no restarts. For models
    /// assembled directly (synthetic models in tests, benches and the daemon's load generator).
    pub fn untrained(channels: usize, components: usize) -> TrainReport {
        TrainReport {
            frames_total: 1,
            frames_used: 1,
            channels,
            dead_channels: vec![],
            components,
            variance_kept: 0.99,
            eigenvalues: vec![],
            contrast: "logcosh".into(),
            algorithm: "symmetric".into(),
            tol: 1e-6,
            max_iter: 100,
            restarts: vec![],
            best_restart: 0,
            stability: vec![],
        }
    }
}
