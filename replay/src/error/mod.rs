//! Errors of reading, writing and validating takes.

pub mod c3d;

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
    /// A sample not flagged missing lies further than [`crate::take::MAX_COORDINATE_MM`]
    /// from the origin along an axis: no capture volume is that large, the data are corrupt.
    #[error(
        "marker {marker:?} at frame index {frame} is at {value:e} mm: past 10 km, not a position (corrupt data?)"
    )]
    Implausible {
        /// 0-based frame index.
        frame: usize,
        /// Marker label.
        marker: String,
        /// The coordinate, mm.
        value: f32,
    },
}

/// Why a take could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The underlying reader failed.
    #[error("cannot read")]
    Io(#[from] std::io::Error),
    /// The file is not one to read (a device, a FIFO, too large).
    #[error(transparent)]
    Open(#[from] crate::file::OpenError),
    /// The file extension names no supported format.
    #[error("unknown take format {0:?} (expected .c3d, .trc or .csv)")]
    UnknownFormat(PathBuf),
    /// The file's structure is wrong; the text names what and where.
    #[error("{0}")]
    Malformed(String),
    /// The file declares units that cannot be converted to millimetres.
    #[error("unknown units {0:?} (expected mm, cm or m)")]
    UnknownUnits(String),
    /// A C3D file is damaged or inconsistent; the error names what.
    #[error(transparent)]
    C3d(#[from] c3d::C3dError),
    /// The content parsed but breaks a take invariant.
    #[error(transparent)]
    Invalid(#[from] TakeError),
    /// A text line is not valid UTF-8.
    #[error("line {line} is not valid utf-8")]
    NotUtf8 {
        /// 1-based line number.
        line: usize,
    },
    /// A text line longer than any take's (a binary file, or text without newlines): refused
    /// before it is held in memory.
    #[error("line {line} is over {max_mib} MiB without a newline: not a TRC or CSV take (is the extension right?)")]
    LineTooLong {
        /// 1-based line number.
        line: usize,
        /// The longest line read, MiB.
        max_mib: u64,
    },
    /// The input ended before a required header line.
    #[error("input ends at line {line}, expected {expected}")]
    UnexpectedEnd {
        /// 1-based number of the line that is missing.
        line: usize,
        /// What that line should have held.
        expected: &'static str,
    },
    /// A header line does not have the shape the format requires.
    #[error("line {line}: expected {expected}, found {found:?}")]
    BadHeader {
        /// 1-based line number.
        line: usize,
        /// What the line should hold.
        expected: &'static str,
        /// The offending text.
        found: String,
    },
    /// One cell does not hold what its column requires (a non-numeric or infinite sample, a bad
    /// frame number).
    #[error("line {line}, column {column} ({field}): expected {expected}, found {found:?}")]
    BadCell {
        /// 1-based line number.
        line: usize,
        /// 1-based column number.
        column: usize,
        /// What the column holds, e.g. `Chin y` or `Frame#`.
        field: String,
        /// What the cell should hold.
        expected: &'static str,
        /// The offending cell text.
        found: String,
    },
    /// A row has more (or, where the format forbids it, fewer) cells than the header.
    #[error("line {line}: expected {expected} columns, found {found}")]
    ColumnCount {
        /// 1-based line number.
        line: usize,
        /// Columns the header defines.
        expected: usize,
        /// Columns the row holds.
        found: usize,
    },
    /// A data row is cut off: it ends inside one marker's x/y/z cells, or it is a short last row
    /// with no newline.
    #[error("line {line}: row is cut off at marker {marker:?} after {cells} of its 3 cells")]
    TruncatedRow {
        /// 1-based line number.
        line: usize,
        /// Label of the cut marker.
        marker: String,
        /// Cells of that marker present (0, 1 or 2).
        cells: usize,
    },
    /// Frame numbers are not consecutive.
    #[error("line {line}: expected frame number {expected}, found {found}")]
    FrameGap {
        /// 1-based line number.
        line: usize,
        /// The frame number that should follow.
        expected: i64,
        /// The frame number the row holds.
        found: i64,
    },
    /// The header's frame count disagrees with the data rows (a truncated file, usually).
    #[error("header declares {declared} frames but the data holds {found}")]
    FrameCountMismatch {
        /// Frames the header declares.
        declared: usize,
        /// Data rows found.
        found: usize,
    },
    /// The header's marker count disagrees with the marker names it lists.
    #[error("header declares {declared} markers but names {found}")]
    MarkerCountMismatch {
        /// Markers the header declares.
        declared: usize,
        /// Marker names found.
        found: usize,
    },
    /// No frame rate is declared and too few frames exist to derive one.
    #[error("cannot derive a frame rate from {frames} frame(s); declare one with `# rate_hz=...`")]
    NoRate {
        /// Frames in the file.
        frames: usize,
    },
    /// The time column does not advance evenly enough to derive a frame rate.
    #[error(
        "line {line}: time step {step_s} s is not within 0.5-1.5x the mean step {mean_step_s} s"
    )]
    UnevenTime {
        /// 1-based line number of the later row.
        line: usize,
        /// The step from the previous row, seconds.
        step_s: f64,
        /// The mean step over the file, seconds.
        mean_step_s: f64,
    },
}

/// Why a take could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The underlying writer failed.
    #[error("cannot write")]
    Io(#[from] std::io::Error),
    /// The file extension names no supported format.
    #[error("unknown take format {0:?} (expected .c3d, .trc or .csv)")]
    UnknownFormat(PathBuf),
    /// The take cannot be represented in the target format; the text says why.
    #[error("{0}")]
    Unrepresentable(String),
    /// The take exceeds what a C3D file can hold.
    #[error(transparent)]
    C3dLimit(#[from] c3d::C3dLimitError),
    /// A marker label holds a character the text format uses as a separator.
    #[error(
        "marker label {label:?} contains {forbidden:?}, which {format} cannot hold in a label"
    )]
    LabelUnrepresentable {
        /// The format being written (`trc`, `csv`).
        format: &'static str,
        /// The label.
        label: String,
        /// The offending character.
        forbidden: char,
    },
    /// The take breaks an invariant.
    #[error(transparent)]
    Invalid(#[from] TakeError),
    /// A recording stopped before it was finished, by a write error (a full disk) or a disk
    /// that fell too far behind: the file is closed valid with the frames that fit, its header
    /// counting them. The message names the cause (the OS's own words: "No space left on
    /// device").
    #[error("stopped after {frames} frames, which the file keeps: {cause}")]
    Stopped {
        /// Frames the file keeps.
        frames: u64,
        /// What stopped it.
        cause: std::io::Error,
    },
    /// A take written in blocks ended with another frame count than its header declared.
    #[error("header declares {declared} frames but {written} were written")]
    FrameCountMismatch {
        /// Frames the header declares.
        declared: usize,
        /// Frames written.
        written: usize,
    },
}
