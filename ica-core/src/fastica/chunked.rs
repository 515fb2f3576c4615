//! Map/merge kernels of FastICA over whitened chunks: one pass over the data per iteration.
//!
//! A chunk is `frames x m` values, frame after frame (`m` whitened values each), as
//! [`crate::whiten::Whitener::whiten_into`] writes them; `f32` or `f64`. Each kernel works in
//! blocks of [`BLOCK_FRAMES`] frames converted to f64, so its memory does not grow with the
//! chunk, and allocates nothing after its first block.

use nalgebra::DMatrix;

use super::fused::Fused;
use super::Contrast;
use crate::input::FitError;
use crate::linalg::{cols, cols_mut, product};

/// Frames per block: the block and its sources (2 x 1024 x m f64) stay in L2 at m = 20.
pub(crate) const BLOCK_FRAMES: usize = 1024;

/// The sums one pass of the fixed-point update needs, for the rows of a rotation `W` (`k x m`):
/// `B = Σ z g(W z)ᵀ` (`m x k`) and `Σ g'(W z)` per row, over every frame.
///
/// Fold chunks with [`UpdateAccumulator::add_chunk`], partials from other threads with
/// [`UpdateAccumulator::merge`] (in chunk order for bit-identical runs), then
/// [`UpdateAccumulator::finish`] for the symmetric step, or hand it to
/// [`super::Refiner::handle_update`].
#[derive(Debug, Clone)]
pub struct UpdateAccumulator {
    w: DMatrix<f64>,
    contrast: Contrast,
    step: usize,
    frames: usize,
    sums: Fused,
    scratch: Scratch,
}

/// The full (undamped) symmetric step.
#[derive(Debug, Clone)]
pub struct Update {
    /// `W⁺ = (E{g(Wz) zᵀ} - diag(E{g'(Wz)}) W)`, symmetrically decorrelated.
    pub w: DMatrix<f64>,
    /// `max_i |1 - |<w⁺_i, w_i>||`: 0 when no row turned.
    pub delta: f64,
}

impl UpdateAccumulator {
    /// An empty accumulator for the rotation `w` (`k x m`, usually square).
    pub fn new(w: &DMatrix<f64>, contrast: Contrast) -> Self {
        Self::for_step(w.clone(), contrast, 0)
    }

    /// An empty accumulator tagged with the refinement step it belongs to.
    pub(crate) fn for_step(w: DMatrix<f64>, contrast: Contrast, step: usize) -> Self {
        Self {
            sums: Fused::new(&w),
            w,
            contrast,
            step,
            frames: 0,
            scratch: Scratch::default(),
        }
    }

    /// Frames added so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Adds a chunk of whitened frames (`frames x m`, frame after frame).
    ///
    /// # Errors
    /// [`FitError::RaggedSamples`] if the length is not a multiple of `m`.
    pub fn add_chunk<T: Copy + Into<f64>>(&mut self, z: &[T]) -> Result<(), FitError> {
        let m = self.w.ncols();
        check_frames(z, m)?;
        for chunk in z.chunks(BLOCK_FRAMES * m) {
            let nb = self.scratch.load(chunk, m);
            self.sums.add(&self.scratch.z, self.contrast);
            self.frames += nb;
        }
        Ok(())
    }

    /// Adds the sums of `other`, made for the same rotation.
    ///
    /// # Errors
    /// [`FitError::AccumulatorMismatch`] if `other` belongs to another step or rotation shape.
    pub fn merge(&mut self, other: UpdateAccumulator) -> Result<(), FitError> {
        if other.step != self.step || other.w.shape() != self.w.shape() {
            return Err(FitError::AccumulatorMismatch);
        }
        self.frames += other.frames;
        self.sums.merge(&other.sums);
        Ok(())
    }

    /// The full symmetric step from the sums (the chunked [`super::Refiner`] adds the step
    /// damping that cycling runs need).
    ///
    /// # Errors
    /// [`FitError::TooFewFrames`] if no frame was added.
    pub fn finish(self) -> Result<Update, FitError> {
        let mut w = self.w.clone();
        let delta = self.step_into(1.0, &mut w)?;
        Ok(Update { w, delta })
    }

    /// The step this accumulator was made for.
    pub(crate) fn step(&self) -> usize {
        self.step
    }

    /// The symmetric step damped by `mu` into `next` (same shape as `W`); returns the change.
    pub(crate) fn step_into(self, mu: f64, next: &mut DMatrix<f64>) -> Result<f64, FitError> {
        let inv_t = self.inv_frames()?;
        let (b, mut gp) = self.sums.sums();
        gp.iter_mut().for_each(|g| *g *= inv_t);
        Ok(super::symmetric::next_rotation(
            &self.w, &b, &gp, inv_t, mu, next,
        ))
    }

    /// The one-unit step of row 0: `E{z g(wᵀz)} - E{g'(wᵀz)} w` (not normalised).
    pub(crate) fn one_unit(&self) -> Result<Vec<f64>, FitError> {
        let inv_t = self.inv_frames()?;
        let (b, gp) = self.sums.sums();
        let gp = gp[0] * inv_t;
        Ok((0..self.w.ncols())
            .map(|j| b[(j, 0)] * inv_t - gp * self.w[(0, j)])
            .collect())
    }

    fn inv_frames(&self) -> Result<f64, FitError> {
        if self.frames == 0 {
            return Err(FitError::TooFewFrames {
                used: 0,
                total: 0,
                needed: 1,
            });
        }
        Ok(1.0 / self.frames as f64)
    }
}

/// Per-component sums over the frames of `u = W z`: `Σ G(u)` for the negentropy, and the first
/// three power sums for the skewness the sign convention needs, so the sources never have to
/// be kept.
#[derive(Debug, Clone)]
pub struct SourceMoments {
    w: DMatrix<f64>,
    contrast: Contrast,
    frames: usize,
    /// Per component: `Σ G(u)`, `Σ u`, `Σ u²`, `Σ u³`.
    sums: Vec<[f64; 4]>,
    scratch: Scratch,
}

impl SourceMoments {
    /// Empty sums for the rotation `w` (`m x m`).
    pub fn new(w: &DMatrix<f64>, contrast: Contrast) -> Self {
        Self {
            w: w.clone(),
            contrast,
            frames: 0,
            sums: vec![[0.0; 4]; w.nrows()],
            scratch: Scratch::default(),
        }
    }

    /// Frames added so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Adds a chunk of whitened frames (`frames x m`, frame after frame).
    ///
    /// # Errors
    /// [`FitError::RaggedSamples`] if the length is not a multiple of `m`.
    pub fn add_chunk<T: Copy + Into<f64>>(&mut self, z: &[T]) -> Result<(), FitError> {
        let m = self.w.ncols();
        check_frames(z, m)?;
        for chunk in z.chunks(BLOCK_FRAMES * m) {
            let nb = self.scratch.load(chunk, m);
            let (_, y) = self.scratch.sources(&self.w, nb);
            for (sum, col) in self.sums.iter_mut().zip(y.chunks_exact(nb)) {
                for &u in col {
                    let u2 = u * u;
                    sum[0] += self.contrast.big_g(u);
                    sum[1] += u;
                    sum[2] += u2;
                    sum[3] += u2 * u;
                }
            }
            self.frames += nb;
        }
        Ok(())
    }

    /// Adds the sums of `other`, made for the same rotation.
    ///
    /// # Errors
    /// [`FitError::AccumulatorMismatch`] if `other` was made for another rotation.
    pub fn merge(&mut self, other: SourceMoments) -> Result<(), FitError> {
        if other.w != self.w {
            return Err(FitError::AccumulatorMismatch);
        }
        self.frames += other.frames;
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
        }
        Ok(())
    }

    /// The rotation the sums are for.
    pub(crate) fn w(&self) -> &DMatrix<f64> {
        &self.w
    }

    /// Total negentropy approximation `Σ_i (E G(u_i) - E G(ν))²` (0 with no frames).
    pub fn negentropy(&self) -> f64 {
        if self.frames == 0 {
            return 0.0;
        }
        let gaussian = self.contrast.gaussian_expectation();
        let n = self.frames as f64;
        self.sums
            .iter()
            .map(|s| (s[0] / n - gaussian).powi(2))
            .sum()
    }

    /// Sample skewness `E (u - ū)³ / σ³` of each component (0 for a constant one or no frames).
    pub fn skewness(&self) -> Vec<f64> {
        let n = self.frames.max(1) as f64;
        self.sums
            .iter()
            .map(|s| {
                let mean = s[1] / n;
                let m2 = s[2] / n - mean * mean;
                let m3 = s[3] / n - 3.0 * mean * s[2] / n + 2.0 * mean * mean * mean;
                if m2 <= 0.0 {
                    0.0
                } else {
                    m3 / m2.powf(1.5)
                }
            })
            .collect()
    }
}

/// A whitened chunk must hold whole frames of `m` values.
fn check_frames<T>(z: &[T], m: usize) -> Result<(), FitError> {
    if m == 0 || z.len() % m != 0 {
        return Err(FitError::RaggedSamples {
            len: z.len(),
            channels: m,
        });
    }
    Ok(())
}

/// Working memory of a kernel: one block of frames and its sources.
#[derive(Debug, Clone, Default)]
struct Scratch {
    /// `m x block`, one frame per column.
    z: Vec<f64>,
    /// `block x k`, one component per column.
    y: Vec<f64>,
}

impl Scratch {
    /// Loads a block of whole frames as f64; returns its frame count.
    fn load<T: Copy + Into<f64>>(&mut self, block: &[T], m: usize) -> usize {
        self.z.clear();
        self.z.extend(block.iter().map(|&v| v.into()));
        block.len() / m
    }

    /// `Y = Zᵀ Wᵀ` for the loaded block of `nb` frames: returns the block and `Y` (`nb x k`).
    fn sources(&mut self, w: &DMatrix<f64>, nb: usize) -> (&[f64], &mut [f64]) {
        let (k, m) = w.shape();
        self.y.resize(BLOCK_FRAMES.max(nb) * k, 0.0);
        product(
            cols_mut(&mut self.y, nb, k),
            cols(&self.z, m, nb).transpose(),
            cols(w.as_slice(), k, m).transpose(),
        );
        (&self.z, &mut self.y[..nb * k])
    }
}
