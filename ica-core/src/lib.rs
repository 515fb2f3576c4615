//! The numerics of emoshift, after Cao, Faloutsos & Pighin, "Unsupervised Learning for Speech
//! Motion Editing" (2003). No I/O: every function takes data and returns values.
//!
//! # From captures to a model
//!
//! Frames `x` (markers × xyz, mm) are centred and PCA-whitened ([`whiten`], keeping a share of
//! the variance or stopping at the noise floor), [`fastica`] finds independent components `u`,
//! and [`fit`] joins them into the model `x ≈ E{x} + M·u` ([`model::IcaModel`], `M = P·A`).
//! Around the fit: [`impute`] fills marker gaps for training, [`stabilise`] takes head motion
//! out with a rigid reference, [`measure`] and [`quality`] say how well the model holds.
//! Paired takes, aligned by [`dtw`], reveal the emotion components ([`interpret`]).
//!
//! # A live frame's path through ica-core
//!
//! 1. [`stabilise`]: the head pose from the rigid reference, the frame into head coordinates.
//! 2. [`project::Projector`]: `u = M⁺(x − E{x})`, masked where markers are missing.
//! 3. [`edit::FrameEdit`] (or the daemon's live edit state over [`model::SpaceTarget`]):
//!    Translate, Copy & Replace, Copy & Add in component space.
//! 4. [`project::Projector`] again: `x' = E{x} + M·u'`, and the head pose put back.
//!
//! Main types: [`IcaModel`], [`FastIcaParams`], [`TrainReport`], [`Projector`],
//! [`FrameEdit`], [`EmotionLevels`].
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod dtw;
pub mod edit;
pub mod fastica;
pub mod fit;
pub mod frame;
pub mod impute;
pub mod input;
pub mod interpret;
mod linalg;
pub mod measure;
pub mod mixture;
pub mod model;
pub mod project;
pub mod quality;
pub mod report;
pub mod robust;
pub mod stabilise;
pub mod whiten;

pub use fit::{amari_index, FastIcaParams, FitData, FitError, FitOutput};
pub use report::{Refinement, RestartReport, TrainReport};

pub use edit::{EditError, FrameEdit};
pub use model::{EmotionLevels, IcaModel, ModelError, Role, FORMAT_VERSION};
pub use project::{FrameError, FrameStatus, Projector};
