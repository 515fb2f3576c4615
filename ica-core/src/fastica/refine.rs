//! FastICA iterations driven pass by pass: a sans-IO state machine over
//! [`UpdateAccumulator`]s, and a simple in-memory driver.
//!
//! Call order: [`Refiner::new`]; then while [`Refiner::is_done`] is false, take
//! [`Refiner::accumulator`], fold every whitened chunk into it (and merge partials), and hand
//! it back with [`Refiner::handle_update`]; finally [`Refiner::outcome`]. Each round is one
//! pass over the data and one iteration, with the same steps (step-size control included) as
//! the in-memory iteration, so on the same data both end at the same rotation up to rounding.

use nalgebra::{DMatrix, DVector};

use super::chunked::UpdateAccumulator;
use super::deflation::orthonormalise;
use super::symmetric::{decorrelate, StepControl};
use super::{Algorithm, Contrast};
use crate::input::FitError;

/// What the iteration runs: update rule, contrast, stopping rule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineSettings {
    /// Contrast function.
    pub contrast: Contrast,
    /// Update rule.
    pub algorithm: Algorithm,
    /// Convergence tolerance on `max |1 - |diag(W_new W_old^T)||`.
    pub tol: f64,
    /// Iteration cap (per component for the deflation rule).
    pub max_iter: usize,
}

/// How an iteration ended.
#[derive(Debug, Clone, PartialEq)]
pub struct RefineOutcome {
    /// The rotation, `m x m`, orthonormal rows.
    pub w: DMatrix<f64>,
    /// Iterations run (the largest per-component count for the deflation rule).
    pub iterations: usize,
    /// Whether the change fell below the tolerance (every component, for deflation).
    pub converged: bool,
    /// The last change (the largest final change of any component, for deflation).
    pub last_delta: f64,
}

/// The deflation rule's position: component `p` is being iterated from `v`.
#[derive(Debug, Clone)]
struct OneUnit {
    w0: DMatrix<f64>,
    p: usize,
    v: DVector<f64>,
}

/// FastICA iterations fed one pass at a time (see the module docs).
#[derive(Debug, Clone)]
pub struct Refiner {
    settings: RefineSettings,
    /// Symmetric: the current rotation. Deflation: the finished rows, then zeros.
    w: DMatrix<f64>,
    next: DMatrix<f64>,
    step: StepControl,
    /// Iterations of the current run (component, for deflation).
    it: usize,
    /// Passes handled: tags accumulators so a stale one is refused.
    passes: usize,
    one_unit: Option<OneUnit>,
    /// Set when done.
    outcome: Option<RefineOutcome>,
    /// Deflation: the largest iteration count and final change so far, and whether all converged.
    summary: (usize, f64, bool),
}

impl Refiner {
    /// Starts from `w0` (`m x m`; rows need not be orthonormal: the update decorrelates them).
    pub fn new(w0: DMatrix<f64>, settings: RefineSettings) -> Self {
        let m = w0.nrows();
        let mut refiner = Self {
            settings,
            w: DMatrix::zeros(m, m),
            next: DMatrix::zeros(m, m),
            step: StepControl::new(),
            it: 0,
            passes: 0,
            one_unit: None,
            outcome: None,
            summary: (0, 0.0, true),
        };
        match settings.algorithm {
            Algorithm::Symmetric => {
                refiner.w = w0;
                decorrelate(&mut refiner.w);
            }
            Algorithm::Deflation => {
                let mut v: DVector<f64> = w0.row(0).transpose();
                orthonormalise(&mut v, &refiner.w, 0);
                refiner.one_unit = Some(OneUnit { w0, p: 0, v });
            }
        }
        refiner
    }

    /// Whether the iteration has ended (converged or at the cap).
    pub fn is_done(&self) -> bool {
        self.outcome.is_some()
    }

    /// The result, once done.
    pub fn outcome(&self) -> Option<&RefineOutcome> {
        self.outcome.as_ref()
    }

    /// Iterations run so far (passes handled).
    pub fn passes(&self) -> usize {
        self.passes
    }

    /// An empty accumulator for the next pass (for the current rotation, or the current
    /// component's row under the deflation rule).
    pub fn accumulator(&self) -> UpdateAccumulator {
        let w = match &self.one_unit {
            Some(one) => DMatrix::from_row_slice(1, one.v.len(), one.v.as_slice()),
            None => self.w.clone(),
        };
        UpdateAccumulator::for_step(w, self.settings.contrast, self.passes)
    }

    /// Takes one iteration from a pass's sums; returns whether the iteration is now done.
    ///
    /// # Errors
    /// [`FitError::AccumulatorMismatch`] for an accumulator not made by the latest
    /// [`Refiner::accumulator`] (or after the end), [`FitError::TooFewFrames`] if it saw no frame.
    pub fn handle_update(&mut self, acc: UpdateAccumulator) -> Result<bool, FitError> {
        if self.is_done() || acc.step() != self.passes {
            return Err(FitError::AccumulatorMismatch);
        }
        if self.one_unit.is_some() {
            self.one_unit_step(&acc)?;
        } else {
            self.symmetric_step(acc)?;
        }
        self.passes += 1;
        Ok(self.is_done())
    }

    fn symmetric_step(&mut self, acc: UpdateAccumulator) -> Result<(), FitError> {
        let delta = acc.step_into(self.step.mu, &mut self.next)?;
        std::mem::swap(&mut self.w, &mut self.next);
        self.it += 1;
        let converged = delta < self.settings.tol;
        if converged || self.it == self.settings.max_iter {
            self.outcome = Some(RefineOutcome {
                w: self.w.clone(),
                iterations: self.it,
                converged,
                last_delta: delta,
            });
        } else {
            self.step.after(self.it);
        }
        Ok(())
    }

    fn one_unit_step(&mut self, acc: &UpdateAccumulator) -> Result<(), FitError> {
        let mut next = DVector::from_vec(acc.one_unit()?);
        let one = self
            .one_unit
            .as_mut()
            .expect("called under the deflation rule");
        orthonormalise(&mut next, &self.w, one.p);
        let delta = (1.0 - next.dot(&one.v).abs()).abs();
        one.v = next;
        self.it += 1;
        let converged = delta < self.settings.tol;
        if !converged && self.it < self.settings.max_iter {
            return Ok(());
        }
        let (iterations, last_delta, all) = &mut self.summary;
        *iterations = (*iterations).max(self.it);
        *last_delta = last_delta.max(delta);
        *all &= converged;
        self.w.row_mut(one.p).copy_from(&one.v.transpose());
        one.p += 1;
        self.it = 0;
        if one.p < self.w.nrows() {
            let mut v: DVector<f64> = one.w0.row(one.p).transpose();
            orthonormalise(&mut v, &self.w, one.p);
            one.v = v;
        } else {
            self.outcome = Some(RefineOutcome {
                w: self.w.clone(),
                iterations: self.summary.0,
                converged: self.summary.2,
                last_delta: self.summary.1,
            });
        }
        Ok(())
    }
}

/// Receives whitened chunks (`frames x m`, frame after frame) during a pass.
pub type ChunkSink<'a, T> = dyn FnMut(&[T]) + 'a;

/// Runs the iteration from `w0` over whitened data held by the caller: `for_each_chunk` is
/// called once per pass and must call its argument with every chunk (`frames x m`), in any
/// fixed cut. The in-memory counterpart of a daemon's pass loop, for tests and small data.
///
/// # Errors
/// A chunk that is not a whole number of frames, or a pass with no frame: see [`FitError`].
pub fn refine_chunked<T: Copy + Into<f64>>(
    w0: DMatrix<f64>,
    settings: RefineSettings,
    for_each_chunk: &mut dyn FnMut(&mut ChunkSink<'_, T>),
) -> Result<RefineOutcome, FitError> {
    let mut refiner = Refiner::new(w0, settings);
    while !refiner.is_done() {
        let mut acc = refiner.accumulator();
        let mut failed = None;
        for_each_chunk(&mut |z| {
            if failed.is_none() {
                failed = acc.add_chunk(z).err();
            }
        });
        if let Some(e) = failed {
            return Err(e);
        }
        refiner.handle_update(acc)?;
    }
    Ok(refiner
        .outcome()
        .cloned()
        .expect("the loop ends when the refiner is done"))
}

#[cfg(test)]
mod tests;
