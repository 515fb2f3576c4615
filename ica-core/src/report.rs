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
    /// Total negentropy approximation of the solution (larger is better).
    pub negentropy: f64,
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
}
