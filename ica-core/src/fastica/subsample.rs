//! The restarts' exploration subsample, collected while the whitened frames stream past.
//!
//! [`super::run`] explores restarts on every `k`-th used frame, `k = frames / EXPLORE_FRAMES`,
//! from the first. The stride needs the number of used frames, which the statistics pass
//! counts for free before the whitening pass, so the subsample is exactly the in-memory one:
//! a reservoir would draw a different, random set (and different restart results) for no gain.

use nalgebra::DMatrix;

use super::EXPLORE_FRAMES;
use crate::input::FitError;

/// Which frames the whitening pass keeps for the restarts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SubsamplePlan {
    /// A short take (under twice [`EXPLORE_FRAMES`] used frames): keep every frame, run the
    /// whole fit in memory exactly as [`crate::FastIcaParams::fit`] does.
    All,
    /// Keep every `stride`-th frame; the restarts run on those in memory and only the winner is
    /// refined over the stream.
    Strided(usize),
    /// A long take with a single restart: keep nothing, that restart runs over the stream.
    Nothing,
}

impl SubsamplePlan {
    /// The plan for `frames` used frames and `restarts` restarts (matches the in-memory fit).
    pub fn new(frames: usize, restarts: usize) -> Self {
        if frames < 2 * EXPLORE_FRAMES {
            SubsamplePlan::All
        } else if restarts < 2 {
            SubsamplePlan::Nothing
        } else {
            SubsamplePlan::Strided(frames / EXPLORE_FRAMES)
        }
    }

    fn stride(self) -> usize {
        match self {
            SubsamplePlan::All => 1,
            SubsamplePlan::Strided(k) => k,
            SubsamplePlan::Nothing => 0,
        }
    }
}

/// Collects the exploration subsample from whitened chunks pushed in frame order.
#[derive(Debug, Clone)]
pub struct Subsample {
    m: usize,
    plan: SubsamplePlan,
    seen: usize,
    /// Kept frames, `m` values each.
    z: Vec<f64>,
}

impl Subsample {
    /// An empty collector for `m` components following `plan` over `frames` used frames
    /// (reserves the whole subsample now, so pushing never allocates).
    pub fn new(m: usize, frames: usize, plan: SubsamplePlan) -> Self {
        let stride = plan.stride();
        let kept = if stride == 0 {
            0
        } else {
            frames.div_ceil(stride)
        };
        Self {
            m,
            plan,
            seen: 0,
            z: Vec::with_capacity(kept * m),
        }
    }

    /// The plan it follows.
    pub fn plan(&self) -> SubsamplePlan {
        self.plan
    }

    /// Frames pushed so far.
    pub fn frames_seen(&self) -> usize {
        self.seen
    }

    /// Frames kept so far.
    pub fn frames_kept(&self) -> usize {
        self.z.len() / self.m.max(1)
    }

    /// Pushes the next whitened frames (`frames x m`, frame after frame, in frame order).
    ///
    /// # Errors
    /// [`FitError::RaggedSamples`] if the length is not a multiple of `m`.
    pub fn push<T: Copy + Into<f64>>(&mut self, z: &[T]) -> Result<(), FitError> {
        let m = self.m;
        if m == 0 || z.len() % m != 0 {
            return Err(FitError::RaggedSamples {
                len: z.len(),
                channels: m,
            });
        }
        let stride = self.plan.stride();
        for frame in z.chunks_exact(m) {
            if stride > 0 && self.seen % stride == 0 {
                self.z.extend(frame.iter().map(|&v| v.into()));
            }
            self.seen += 1;
        }
        Ok(())
    }

    /// The kept frames as the `m x n` matrix the in-memory FastICA takes.
    pub(crate) fn into_matrix(self) -> DMatrix<f64> {
        let n = self.frames_kept();
        DMatrix::from_vec(self.m, n, self.z)
    }
}
