//! Recorded takes on disk (C3D, TRC, CSV), the synthetic face generator and the replay pacer.
//!
//! Main types: [`Take`] (labels, rate, first frame, positions in mm, missing mask), [`Format`],
//! [`load`] and [`save`]; [`pacer::Pacer`], the sans-IO schedule `emoshift replay` sends a take
//! on; [`recorder::Recorder`], which writes a take frame by frame as it arrives;
//! [`blocks::BlockReader`] and [`TakeWriter`], which read and write a take in blocks of
//! frames so a long take never has to be held whole.
//!
//! This crate must not know about ICA models (the daemon joins takes and models).
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod blocks;
pub mod c3d;
pub mod csv;
pub mod decimal;
mod durable;
pub mod error;
pub mod file;
pub mod format;
pub mod pacer;
pub mod recorder;
pub mod repair;
mod resample;
pub mod session;
pub mod synth;
pub mod take;
pub mod trc;
pub mod writer;

pub use error::{ReadError, TakeError, WriteError};
pub use format::{load, load_limited, load_with, save, write_as, C3dDecoding, Format};
pub use take::{Take, Units};
pub use writer::TakeWriter;
