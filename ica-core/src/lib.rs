//! ica-core
#![warn(missing_docs)]

pub mod report;

pub use report::{RestartReport, TrainReport};
