//! ica-core
#![warn(missing_docs)]

pub mod edit;
pub mod fastica;
pub mod fit;
pub mod model;
pub mod project;
pub mod report;
pub mod whiten;

pub use report::{RestartReport, TrainReport};
