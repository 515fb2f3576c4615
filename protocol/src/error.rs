//! Error types: [`DecodeError`] for the per-datagram path, [`EncodeError`] for outputs.

/// Why a datagram or message was rejected.
///
/// Small and `Copy` so that the hot path never allocates or formats; [`DecodeError::kind`]
/// gives a field-less key for per-kind drop counters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// The datagram was empty.
    #[error("empty datagram")]
    Empty,
    /// The datagram is longer than the configured maximum.
    #[error("datagram of {len} bytes exceeds the maximum of {max}")]
    Oversize {
        /// Datagram length in bytes.
        len: usize,
        /// Configured maximum.
        max: usize,
    },
    /// The data ended before a complete value could be read.
    #[error("truncated at byte {offset}")]
    Truncated {
        /// Offset where the missing value starts.
        offset: usize,
    },
    /// Bytes were left after a complete message or bundle element.
    #[error("{extra} trailing bytes after byte {offset}")]
    TrailingBytes {
        /// Offset where the unexpected bytes start.
        offset: usize,
        /// How many bytes were left over.
        extra: usize,
    },
    /// The address is not `/...` UTF-8, nor `#bundle`.
    #[error("bad address or bundle tag at byte {offset}")]
    BadAddress {
        /// Offset of the address string.
        offset: usize,
    },
    /// The address is well formed but not one this decoder handles.
    #[error("unknown address")]
    UnknownAddress,
    /// The message has no type tag string (OSC 1.0 requires one starting with `,`).
    #[error("missing type tag string at byte {offset}")]
    MissingTypeTags {
        /// Offset where the type tag string was expected.
        offset: usize,
    },
    /// A type tag this crate does not know, or unbalanced `[` `]`.
    #[error("unsupported type tag {tag:?} at byte {offset}")]
    BadTypeTag {
        /// The offending tag byte.
        tag: u8,
        /// Offset of the tag byte.
        offset: usize,
    },
    /// Arrays in the type tags nest deeper than the limit.
    #[error("arrays nest deeper than {max}")]
    ArrayTooDeep {
        /// The limit.
        max: usize,
    },
    /// The type tags are valid OSC but not what this address expects.
    #[error("wrong type tags for this address")]
    WrongTypeTags,
    /// A count does not agree with another (mask vs positions, floats not a multiple of 3, ...).
    #[error("wrong count: expected {expected}, got {got}")]
    WrongCount {
        /// What the other fields imply.
        expected: usize,
        /// What the message holds.
        got: usize,
    },
    /// More markers than the caller's buffer was built for.
    #[error("{markers} markers exceed the buffer's maximum of {max}")]
    TooManyMarkers {
        /// Markers in the message.
        markers: usize,
        /// Buffer capacity in markers.
        max: usize,
    },
    /// A present marker has a NaN or infinite coordinate.
    #[error("marker {marker} has a non-finite coordinate")]
    NonFinite {
        /// Marker index in label order.
        marker: usize,
    },
    /// In the flat form, a marker has some but not all coordinates NaN.
    #[error("marker {marker} is only partly missing")]
    PartlyMissing {
        /// Marker index in label order.
        marker: usize,
    },
    /// Bundles nest deeper than the limit.
    #[error("bundles nest deeper than {max}")]
    BundleTooDeep {
        /// The limit.
        max: usize,
    },
    /// A bundle element size is zero, not a multiple of 4, or runs past the bundle.
    #[error("bad bundle element size {size} at byte {offset}")]
    BadElementSize {
        /// The declared size.
        size: u32,
        /// Offset of the size field.
        offset: usize,
    },
    /// A string argument is not valid UTF-8.
    #[error("string argument at byte {offset} is not utf-8")]
    BadString {
        /// Offset of the string.
        offset: usize,
    },
    /// A value is out of its allowed range (negative count, empty label, ...).
    #[error("value at argument {index} is out of range")]
    OutOfRange {
        /// Argument index in the message.
        index: usize,
    },
    /// A `/mocap/labels` names a marker twice: no frame could say which is which.
    #[error("label at argument {index} repeats an earlier one")]
    DuplicateLabel {
        /// Argument index in the message.
        index: usize,
    },
}

/// Field-less twin of [`DecodeError`], for counters keyed by kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[allow(missing_docs)] // each variant mirrors the DecodeError variant of the same name
pub enum DecodeErrorKind {
    Empty,
    Oversize,
    Truncated,
    TrailingBytes,
    BadAddress,
    UnknownAddress,
    MissingTypeTags,
    BadTypeTag,
    ArrayTooDeep,
    WrongTypeTags,
    WrongCount,
    TooManyMarkers,
    NonFinite,
    PartlyMissing,
    BundleTooDeep,
    BadElementSize,
    BadString,
    OutOfRange,
    DuplicateLabel,
}

impl DecodeErrorKind {
    /// Every kind, in declaration order: `ALL[k.index()] == k`.
    pub const ALL: [DecodeErrorKind; 19] = [
        Self::Empty,
        Self::Oversize,
        Self::Truncated,
        Self::TrailingBytes,
        Self::BadAddress,
        Self::UnknownAddress,
        Self::MissingTypeTags,
        Self::BadTypeTag,
        Self::ArrayTooDeep,
        Self::WrongTypeTags,
        Self::WrongCount,
        Self::TooManyMarkers,
        Self::NonFinite,
        Self::PartlyMissing,
        Self::BundleTooDeep,
        Self::BadElementSize,
        Self::BadString,
        Self::OutOfRange,
        Self::DuplicateLabel,
    ];

    /// Dense index for an array of counters (`[u64; DecodeErrorKind::ALL.len()]`).
    pub fn index(self) -> usize {
        self as usize
    }

    /// Stable snake_case name, for status replies and logs.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Empty => "empty",
            Self::Oversize => "oversize",
            Self::Truncated => "truncated",
            Self::TrailingBytes => "trailing_bytes",
            Self::BadAddress => "bad_address",
            Self::UnknownAddress => "unknown_address",
            Self::MissingTypeTags => "missing_type_tags",
            Self::BadTypeTag => "bad_type_tag",
            Self::ArrayTooDeep => "array_too_deep",
            Self::WrongTypeTags => "wrong_type_tags",
            Self::WrongCount => "wrong_count",
            Self::TooManyMarkers => "too_many_markers",
            Self::NonFinite => "non_finite",
            Self::PartlyMissing => "partly_missing",
            Self::BundleTooDeep => "bundle_too_deep",
            Self::BadElementSize => "bad_element_size",
            Self::BadString => "bad_string",
            Self::OutOfRange => "out_of_range",
            Self::DuplicateLabel => "duplicate_label",
        }
    }
}

impl DecodeError {
    /// The kind of this error, for counters.
    pub fn kind(self) -> DecodeErrorKind {
        use DecodeErrorKind as K;
        match self {
            Self::Empty => K::Empty,
            Self::Oversize { .. } => K::Oversize,
            Self::Truncated { .. } => K::Truncated,
            Self::TrailingBytes { .. } => K::TrailingBytes,
            Self::BadAddress { .. } => K::BadAddress,
            Self::UnknownAddress => K::UnknownAddress,
            Self::MissingTypeTags { .. } => K::MissingTypeTags,
            Self::BadTypeTag { .. } => K::BadTypeTag,
            Self::ArrayTooDeep { .. } => K::ArrayTooDeep,
            Self::WrongTypeTags => K::WrongTypeTags,
            Self::WrongCount { .. } => K::WrongCount,
            Self::TooManyMarkers { .. } => K::TooManyMarkers,
            Self::NonFinite { .. } => K::NonFinite,
            Self::PartlyMissing { .. } => K::PartlyMissing,
            Self::BundleTooDeep { .. } => K::BundleTooDeep,
            Self::BadElementSize { .. } => K::BadElementSize,
            Self::BadString { .. } => K::BadString,
            Self::OutOfRange { .. } => K::OutOfRange,
            Self::DuplicateLabel { .. } => K::DuplicateLabel,
        }
    }
}

/// Why an output could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum EncodeError {
    /// A present marker has a NaN or infinite coordinate; receivers would reject it.
    #[error("marker {marker} has a non-finite coordinate")]
    NonFinite {
        /// Marker index in label order.
        marker: usize,
    },
    /// The encoded packet would exceed the size limit.
    #[error("encoded packet of {len} bytes exceeds the maximum of {max}")]
    Oversize {
        /// Encoded length.
        len: usize,
        /// The limit.
        max: usize,
    },
    /// A string contains a NUL byte, which OSC strings cannot carry.
    #[error("string contains a nul byte")]
    NulInString,
    /// A stream name longer than [`crate::MAX_STREAM_NAME_BYTES`].
    #[error("stream name of {len} bytes exceeds {max}")]
    NameTooLong {
        /// Its length.
        len: usize,
        /// The limit.
        max: usize,
    },
    /// The split size leaves no room for even one marker per part.
    #[error("a part of at most {max} bytes cannot hold one marker")]
    PartTooSmall {
        /// The requested part size.
        max: usize,
    },
}

#[cfg(test)]
mod tests;
