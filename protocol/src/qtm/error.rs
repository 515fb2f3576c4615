//! QTM errors: [`QtmError`], small and `Copy`, for framing, data packets and commands.

/// Why a QTM RT packet, or a part of one, was rejected.
///
/// Small and `Copy` so that the frame path never allocates or formats; [`QtmError::kind`]
/// gives a field-less key for per-kind counters. Offsets count from the packet's first byte
/// (its size field).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum QtmError {
    /// The bytes ended before a complete value could be read.
    #[error("truncated at byte {offset}")]
    Truncated {
        /// Offset where the missing value starts.
        offset: usize,
    },
    /// A packet's size field is below the header's 8 bytes or above the limit.
    #[error("packet size {size} is outside 8..={max}")]
    BadSize {
        /// The size as sent.
        size: u32,
        /// The largest size accepted.
        max: usize,
    },
    /// The packet type is not one of QTM's (0 to 8).
    #[error("unknown packet type {kind}")]
    UnknownType {
        /// The type as sent.
        kind: u32,
    },
    /// A component's size disagrees with its content or the packet.
    #[error("component at byte {offset} announces {declared} bytes, it needs {needed}")]
    ComponentSize {
        /// Offset of the component's size field.
        offset: usize,
        /// Size in the field.
        declared: u32,
        /// Bytes its content needs (or the bytes left in the packet).
        needed: usize,
    },
    /// More markers than the caller's buffer holds.
    #[error("{count} markers, at most {max} accepted")]
    TooManyMarkers {
        /// Markers in the component.
        count: u32,
        /// The caller's capacity.
        max: usize,
    },
    /// A command or string packet that is not NUL-terminated UTF-8.
    #[error("text packet is not NUL-terminated UTF-8")]
    BadText,
    /// Bytes were left after a complete packet.
    #[error("{extra} trailing bytes")]
    TrailingBytes {
        /// How many bytes were left over.
        extra: usize,
    },
    /// An event packet with no event byte, or an unknown one.
    #[error("bad event packet")]
    BadEvent,
}

impl QtmError {
    /// A field-less name for counters (`qtm/dropped_<kind>`).
    pub fn kind(&self) -> &'static str {
        match self {
            QtmError::Truncated { .. } => "truncated",
            QtmError::BadSize { .. } => "bad_size",
            QtmError::UnknownType { .. } => "unknown_type",
            QtmError::ComponentSize { .. } => "component_size",
            QtmError::TooManyMarkers { .. } => "too_many_markers",
            QtmError::BadText => "bad_text",
            QtmError::TrailingBytes { .. } => "trailing_bytes",
            QtmError::BadEvent => "bad_event",
        }
    }
}
