//! The streaming fit as a sans-IO state machine: the caller owns the data, the threads and the
//! spill file, and runs each pass the machine asks for.
//!
//! Call order: [`StreamFit::new`], then loop on [`StreamFit::poll_pass`]:
//! - [`Pass::Moments`]: fold every raw chunk into [`crate::whiten::Moments`] (partials merged
//!   in chunk order), give it to [`StreamFit::handle_moments`];
//! - [`Pass::Whiten`]: whiten every raw chunk with [`StreamFit::whitener`], keep the whitened
//!   chunks (spill them) and push them, in frame order, into [`StreamFit::subsample`]; give the
//!   subsample to [`StreamFit::handle_whitened`], which runs the restarts in memory;
//! - [`Pass::Update`] (once per iteration): fold every whitened chunk into
//!   [`StreamFit::update_accumulator`], give it to [`StreamFit::handle_update`];
//! - [`Pass::Sources`] (once): fold every whitened chunk into [`StreamFit::source_moments`],
//!   give it to [`StreamFit::handle_sources`];
//! - [`Pass::Done`]: nothing left to read, take the output with [`StreamFit::finish`].
//!
//! A short take (under twice [`crate::fastica::EXPLORE_FRAMES`] used frames) is done after the
//! whitening pass: its whitened frames are all in the subsample and it is fitted in memory.

use super::assemble::{self, Solved};
use super::{FastIcaParams, FitError, FitOutput};
use crate::fastica::{
    self, restart_seed, RefineOutcome, RefineSettings, Refiner, SourceMoments, Subsample,
    SubsamplePlan, UpdateAccumulator,
};
use crate::input::Pass;
use crate::whiten::{Moments, Whitener};
use crate::{Refinement, RestartReport};

/// A fit over data read in passes (see the module docs for the call order).
#[derive(Debug)]
pub struct StreamFit {
    params: FastIcaParams,
    channels: usize,
    stage: Stage,
}

#[derive(Debug)]
enum Stage {
    Moments,
    Whiten(Box<Whitener>),
    Update(Box<Streamed>),
    Sources(Box<Streamed>, RefineOutcome),
    Done(Box<FitOutput>),
}

/// State of the passes over whitened data.
#[derive(Debug)]
struct Streamed {
    whitener: Whitener,
    /// The restarts explored on the subsample; `None` when the single restart is the stream's.
    explored: Option<Solved>,
    refiner: Refiner,
}

impl StreamFit {
    /// A fit with `params` over frames of `channels` values.
    ///
    /// # Errors
    /// A bad parameter ([`FastIcaParams::check`]) or [`FitError::NoChannels`].
    pub fn new(params: &FastIcaParams, channels: usize) -> Result<Self, FitError> {
        params.check()?;
        if channels == 0 {
            return Err(FitError::NoChannels);
        }
        Ok(Self {
            params: params.clone(),
            channels,
            stage: Stage::Moments,
        })
    }

    /// The pass to run next.
    pub fn poll_pass(&self) -> Pass {
        match self.stage {
            Stage::Moments => Pass::Moments,
            Stage::Whiten(_) => Pass::Whiten,
            Stage::Update(_) => Pass::Update,
            Stage::Sources(..) => Pass::Sources,
            Stage::Done(_) => Pass::Done,
        }
    }

    /// Channels per frame.
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// FastICA iterations run over the stream so far.
    pub fn iterations(&self) -> usize {
        match &self.stage {
            Stage::Update(s) | Stage::Sources(s, _) => s.refiner.passes(),
            _ => 0,
        }
    }

    /// An empty accumulator for the statistics pass.
    pub fn moments(&self) -> Moments {
        Moments::new(self.channels)
    }

    /// Takes the statistics of every frame and fits the whitening.
    ///
    /// # Errors
    /// Out of order, another width, or what [`Whitener::from_moments`] refuses.
    pub fn handle_moments(&mut self, moments: Moments) -> Result<(), FitError> {
        self.expect(Pass::Moments)?;
        if moments.channels() != self.channels {
            return Err(FitError::ChannelMismatch {
                expected: self.channels,
                got: moments.channels(),
            });
        }
        let whitener = Whitener::from_moments(&moments, self.params.components)?;
        self.stage = Stage::Whiten(Box::new(whitener));
        Ok(())
    }

    /// The fitted whitening, from the whitening pass on.
    pub fn whitener(&self) -> Option<&Whitener> {
        match &self.stage {
            Stage::Whiten(w) => Some(w),
            Stage::Update(s) | Stage::Sources(s, _) => Some(&s.whitener),
            Stage::Moments | Stage::Done(_) => None,
        }
    }

    /// An empty subsample collector for the whitening pass.
    ///
    /// # Errors
    /// [`FitError::UnexpectedPass`] outside the whitening pass.
    pub fn subsample(&self) -> Result<Subsample, FitError> {
        let Stage::Whiten(w) = &self.stage else {
            return Err(self.unexpected(Pass::Whiten));
        };
        let plan = SubsamplePlan::new(w.frames_used, self.params.restarts);
        Ok(Subsample::new(w.components(), w.frames_used, plan))
    }

    /// Takes the whitening pass's subsample and runs the restarts on it in memory.
    ///
    /// # Errors
    /// Out of order, a subsample not made by [`StreamFit::subsample`], or
    /// [`FitError::FrameCountMismatch`] if it did not see every used frame.
    pub fn handle_whitened(&mut self, sub: Subsample) -> Result<(), FitError> {
        let Stage::Whiten(w) = &self.stage else {
            return Err(self.unexpected(Pass::Whiten));
        };
        let plan = SubsamplePlan::new(w.frames_used, self.params.restarts);
        if sub.plan() != plan {
            return Err(FitError::AccumulatorMismatch);
        }
        self.check_count(Pass::Whiten, w.frames_used, sub.frames_seen())?;
        let Stage::Whiten(whitener) = std::mem::replace(&mut self.stage, Stage::Moments) else {
            unreachable!("matched above");
        };
        let s = self.params.settings();
        let settings = self.refine_settings();
        let z = sub.into_matrix();
        self.stage = match plan {
            SubsamplePlan::All => {
                let run = fastica::run(&z, s);
                let (out, _) = self.params.finish_in_memory(&whitener, run);
                Stage::Done(Box::new(out))
            }
            SubsamplePlan::Strided(_) => {
                let run = fastica::explore(&z, s);
                let refiner = Refiner::new(run.w.clone(), settings);
                let explored = Solved {
                    w: run.w,
                    restarts: run.restarts,
                    best: run.best,
                    restart_w: run.restart_w,
                };
                stage_update(*whitener, Some(explored), refiner)
            }
            SubsamplePlan::Nothing => {
                let w0 = fastica::random_start(whitener.components(), restart_seed(s.seed, 0));
                stage_update(*whitener, None, Refiner::new(w0, settings))
            }
        };
        Ok(())
    }

    /// An empty accumulator for the next update pass.
    ///
    /// # Errors
    /// [`FitError::UnexpectedPass`] outside an update pass.
    pub fn update_accumulator(&self) -> Result<UpdateAccumulator, FitError> {
        match &self.stage {
            Stage::Update(s) => Ok(s.refiner.accumulator()),
            _ => Err(self.unexpected(Pass::Update)),
        }
    }

    /// Takes one update pass's sums: one FastICA iteration.
    ///
    /// # Errors
    /// Out of order, a stale accumulator, or one that did not see every used frame.
    pub fn handle_update(&mut self, acc: UpdateAccumulator) -> Result<(), FitError> {
        let Stage::Update(s) = &mut self.stage else {
            return Err(self.unexpected(Pass::Update));
        };
        let used = s.whitener.frames_used;
        if acc.frames() != used {
            return Err(FitError::FrameCountMismatch {
                pass: Pass::Update,
                expected: used,
                got: acc.frames(),
            });
        }
        if !s.refiner.handle_update(acc)? {
            return Ok(());
        }
        let Stage::Update(s) = std::mem::replace(&mut self.stage, Stage::Moments) else {
            unreachable!("matched above");
        };
        let outcome = s.refiner.outcome().cloned().expect("the refiner is done");
        self.stage = Stage::Sources(s, outcome);
        Ok(())
    }

    /// An empty accumulator for the sources pass.
    ///
    /// # Errors
    /// [`FitError::UnexpectedPass`] outside the sources pass.
    pub fn source_moments(&self) -> Result<SourceMoments, FitError> {
        match &self.stage {
            Stage::Sources(_, outcome) => Ok(SourceMoments::new(&outcome.w, self.params.contrast)),
            _ => Err(self.unexpected(Pass::Sources)),
        }
    }

    /// Takes the sources pass's sums and assembles the output.
    ///
    /// # Errors
    /// Out of order, sums for another rotation, or not over every used frame.
    pub fn handle_sources(&mut self, sums: SourceMoments) -> Result<(), FitError> {
        let Stage::Sources(s, outcome) = &self.stage else {
            return Err(self.unexpected(Pass::Sources));
        };
        if sums.w() != &outcome.w {
            return Err(FitError::AccumulatorMismatch);
        }
        self.check_count(Pass::Sources, s.whitener.frames_used, sums.frames())?;
        let Stage::Sources(s, outcome) = std::mem::replace(&mut self.stage, Stage::Moments) else {
            unreachable!("matched above");
        };
        let used = s.whitener.frames_used;
        let solved = self.solved(s.explored, outcome, sums.negentropy(), used);
        let (out, _) = assemble::output(&self.params, &s.whitener, solved, &sums.skewness(), used);
        self.stage = Stage::Done(Box::new(out));
        Ok(())
    }

    /// The fitted output, once done.
    ///
    /// # Errors
    /// [`FitError::UnexpectedPass`] before [`Pass::Done`].
    pub fn finish(self) -> Result<FitOutput, FitError> {
        match self.stage {
            Stage::Done(out) => Ok(*out),
            _ => Err(self.unexpected(Pass::Done)),
        }
    }

    /// The restarts with the stream's result in place: the winner's refinement, or the single
    /// restart itself.
    fn solved(
        &self,
        explored: Option<Solved>,
        outcome: RefineOutcome,
        negentropy: f64,
        frames: usize,
    ) -> Solved {
        match explored {
            Some(mut solved) => {
                solved.restarts[solved.best].refinement = Some(Refinement {
                    frames,
                    iterations: outcome.iterations,
                    converged: outcome.converged,
                    last_delta: outcome.last_delta,
                    negentropy,
                });
                solved.w = outcome.w;
                solved
            }
            None => Solved {
                restarts: vec![RestartReport {
                    seed: restart_seed(self.params.seed, 0),
                    iterations: outcome.iterations,
                    converged: outcome.converged,
                    last_delta: outcome.last_delta,
                    negentropy,
                    frames,
                    refinement: None,
                }],
                restart_w: vec![outcome.w.clone()],
                w: outcome.w,
                best: 0,
            },
        }
    }

    fn refine_settings(&self) -> RefineSettings {
        RefineSettings {
            contrast: self.params.contrast,
            algorithm: self.params.algorithm,
            tol: self.params.tol,
            max_iter: self.params.max_iter,
        }
    }

    fn expect(&self, pass: Pass) -> Result<(), FitError> {
        if self.poll_pass() == pass {
            Ok(())
        } else {
            Err(self.unexpected(pass))
        }
    }

    fn unexpected(&self, got: Pass) -> FitError {
        FitError::UnexpectedPass {
            expected: self.poll_pass(),
            got,
        }
    }

    fn check_count(&self, pass: Pass, expected: usize, got: usize) -> Result<(), FitError> {
        if expected == got {
            Ok(())
        } else {
            Err(FitError::FrameCountMismatch {
                pass,
                expected,
                got,
            })
        }
    }
}

fn stage_update(whitener: Whitener, explored: Option<Solved>, refiner: Refiner) -> Stage {
    Stage::Update(Box::new(Streamed {
        whitener,
        explored,
        refiner,
    }))
}
