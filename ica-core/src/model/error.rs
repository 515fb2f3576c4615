//! What can be wrong with a model, built or loaded.

/// Why a model could not be built, loaded, saved or changed.
///
/// Every variant names the offending value so a user can fix a hand-edited file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    /// Reading the model bytes failed.
    #[error("cannot read model")]
    Read(#[source] std::io::Error),
    /// Writing the model failed.
    #[error("cannot write model")]
    Write(#[source] serde_json::Error),
    /// The bytes are not a model file of the supported layout.
    #[error("malformed model file at line {line}, column {column}")]
    Malformed {
        /// 1-based line of the error.
        line: usize,
        /// 1-based column of the error.
        column: usize,
        /// serde_json's description.
        #[source]
        source: serde_json::Error,
    },
    /// The file has no `format_version` field.
    #[error("model file has no format_version field")]
    MissingVersion,
    /// The file was written by a format this build does not read.
    #[error(
        "model format version {found} is not supported (this build reads version {supported})"
    )]
    UnsupportedVersion {
        /// Version in the file.
        found: u64,
        /// Version this build reads and writes.
        supported: u32,
    },
    /// A matrix or vector has the wrong size.
    #[error("{what} has shape {got:?}, expected {expected:?}")]
    ShapeMismatch {
        /// Which field.
        what: &'static str,
        /// Expected (rows, columns).
        expected: (usize, usize),
        /// Actual (rows, columns).
        got: (usize, usize),
    },
    /// A matrix stored as rows has a row of the wrong length.
    #[error("{what} row {row} has {got} entries, expected {expected}")]
    RaggedRow {
        /// Which field.
        what: &'static str,
        /// 0-based row index.
        row: usize,
        /// Entries in the first row.
        expected: usize,
        /// Entries in this row.
        got: usize,
    },
    /// A NaN or infinite entry (vectors report `col` 0).
    #[error("{what} has a non-finite value at row {row}, column {col}")]
    NonFinite {
        /// Which field.
        what: &'static str,
        /// 0-based row.
        row: usize,
        /// 0-based column.
        col: usize,
    },
    /// The channel count is not markers x 3.
    #[error("model has {channels} channels, which is not a multiple of 3 (x, y, z per marker)")]
    ChannelsNotTriples {
        /// Channels (rows of the mixing matrix).
        channels: usize,
    },
    /// The number of marker labels does not match the channels.
    #[error("model has {channels} channels ({expected} markers) but {got} labels")]
    LabelCount {
        /// Channels.
        channels: usize,
        /// Markers implied by the channels.
        expected: usize,
        /// Labels given.
        got: usize,
    },
    /// Two markers share a label.
    #[error("marker label {label:?} appears twice, at {first} and {second}")]
    DuplicateLabel {
        /// The label.
        label: String,
        /// Index of the first occurrence.
        first: usize,
        /// Index of the second occurrence.
        second: usize,
    },
    /// A marker label is empty.
    #[error("marker label {index} is empty")]
    EmptyLabel {
        /// Index of the label.
        index: usize,
    },
    /// Zero components, or more components than channels.
    #[error("model has {components} components for {channels} channels (need 1..=channels)")]
    ComponentCount {
        /// Components (columns of the mixing matrix).
        components: usize,
        /// Channels.
        channels: usize,
    },
    /// The frame rate is not a positive finite number.
    #[error("frame rate {rate_hz} Hz is not a positive finite number")]
    InvalidRate {
        /// The rate given.
        rate_hz: f64,
    },
    /// The mixing matrix's columns are (nearly) linearly dependent.
    #[error(
        "mixing matrix is rank deficient: smallest singular value {smallest:e} is below \
         {tol:e} x the largest {largest:e}"
    )]
    RankDeficient {
        /// Smallest singular value.
        smallest: f64,
        /// Largest singular value.
        largest: f64,
        /// Relative tolerance ([`super::RANK_TOL`]).
        tol: f64,
    },
    /// The stored unmixing matrix is not the pseudo-inverse of the mixing matrix.
    #[error("unmixing matrix is not the pseudo-inverse of the mixing matrix: {check} is off by {residual:e} (tolerance {tol:e})")]
    NotPseudoInverse {
        /// Which Penrose condition failed (`W·M = I` or `M·W symmetric`).
        check: &'static str,
        /// Largest absolute deviation.
        residual: f64,
        /// Tolerance ([`super::PINV_TOL`]).
        tol: f64,
    },
    /// A component index is outside `0..components`.
    #[error("{what} {index} is out of range: the model has {components} components")]
    ComponentOutOfRange {
        /// Which field or argument.
        what: &'static str,
        /// The index.
        index: usize,
        /// Components in the model.
        components: usize,
    },
    /// An emotion level is not finite, or a point does not have one level per emotion
    /// component.
    #[error("emotion level {name:?} is not finite or does not match the emotion components")]
    NonFiniteLevel {
        /// Name of the level.
        name: String,
    },
    /// Frame-preparation settings do not fit the model.
    #[error("capture settings: {problem}")]
    BadCapture {
        /// What is wrong, e.g. `head reference marker 120 is outside the 109 markers`.
        problem: String,
    },
    /// The training report describes a different shape than the matrices.
    #[error("training report says {what} = {got}, but the model has {expected}")]
    ReportMismatch {
        /// `channels` or `components`.
        what: &'static str,
        /// Value implied by the matrices.
        expected: usize,
        /// Value in the report.
        got: usize,
    },
}
