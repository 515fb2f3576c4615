//! ica-core
#![warn(missing_docs)]

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
mod robust;
pub mod stabilise;
pub mod whiten;

pub use fit::{amari_index, FastIcaParams, FitData, FitError, FitOutput};
pub use report::{Refinement, RestartReport, TrainReport};

pub use edit::{EditError, FrameEdit};
pub use model::{EmotionLevels, IcaModel, ModelError, Role, FORMAT_VERSION};
pub use project::{FrameError, FrameStatus, Projector};
