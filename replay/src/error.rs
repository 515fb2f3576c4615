//! Errors of reading, writing and validating takes.

use std::path::PathBuf;

/// A broken invariant of an in-memory [`Take`](crate::Take).
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum TakeError {
    /// The take has no markers.
    #[error("take has no markers")]
    NoMarkers,
    /// The frame rate is not a positive finite number.
    #[error("frame rate must be positive and finite, got {0}")]
    BadRate(f64),
    /// Buffer lengths disagree with the marker count.
    #[error("{markers} markers but {positions} position values and {mask} mask flags")]
    ShapeMismatch {
        /// Markers.
        markers: usize,
        /// Length of the positions buffer.
        positions: usize,
        /// Length of the mask.
        mask: usize,
    },
    /// A marker label is empty.
    #[error("marker {marker} has an empty label")]
    EmptyLabel {
        /// Marker index.
        marker: usize,
    },
    /// Two markers share a label.
    #[error("marker label {0:?} appears twice")]
    DuplicateLabel(String),
    /// A sample not flagged missing is NaN or infinite.
    #[error("marker {marker:?} at frame index {frame} is not finite")]
    NonFinite {
        /// 0-based frame index.
        frame: usize,
        /// Marker label.
        marker: String,
    },
}

/// Why a take could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The underlying reader failed.
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    /// The file extension names no supported format.
    #[error("unknown take format {0:?} (expected .c3d, .trc or .csv)")]
    UnknownFormat(PathBuf),
    /// The file's structure is wrong; the text names what and where.
    #[error("{0}")]
    Malformed(String),
    /// The file declares units that cannot be converted to millimetres.
    #[error("unknown units {0:?} (expected mm, cm or m)")]
    UnknownUnits(String),
    /// The content parsed but breaks a take invariant.
    #[error(transparent)]
    Invalid(#[from] TakeError),
}

/// Why a take could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The underlying writer failed.
    #[error("cannot write: {0}")]
    Io(#[from] std::io::Error),
    /// The file extension names no supported format.
    #[error("unknown take format {0:?} (expected .c3d, .trc or .csv)")]
    UnknownFormat(PathBuf),
    /// The take cannot be represented in the target format; the text says why.
    #[error("{0}")]
    Unrepresentable(String),
    /// The take breaks an invariant.
    #[error(transparent)]
    Invalid(#[from] TakeError),
}
