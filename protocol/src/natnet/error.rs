//! NatNet errors: [`NatNetError`] (small, `Copy`) for framing, frames and command messages,
//! [`ModelDefError`] with the description it failed in, [`NatNetEncodeError`] for encoders.

/// Why a NatNet datagram or payload was rejected.
///
/// Small and `Copy` so that the frame path never allocates or formats; [`NatNetError::kind`]
/// gives a field-less key for per-kind drop counters. Offsets count from the first byte of
/// the datagram (the message id), so they can be checked against a hex dump.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum NatNetError {
    /// The data ended before a complete value could be read.
    #[error("truncated at byte {offset}")]
    Truncated {
        /// Offset where the missing value starts.
        offset: usize,
    },
    /// Bytes were left after a complete message.
    #[error("{extra} trailing bytes after byte {offset}")]
    TrailingBytes {
        /// Offset where the unexpected bytes start.
        offset: usize,
        /// How many bytes were left over.
        extra: usize,
    },
    /// The header's payload size disagrees with the datagram's length.
    #[error("header announces {declared} payload bytes, datagram holds {actual}")]
    PayloadSize {
        /// Payload size in the header.
        declared: usize,
        /// Bytes after the header in the datagram.
        actual: usize,
    },
    /// A count is negative or larger than the remaining bytes could hold.
    #[error("count {count} at byte {offset} is negative or exceeds the remaining bytes")]
    BadCount {
        /// The count as sent (a negative `i32` shows as negative).
        count: i64,
        /// Offset of the count field.
        offset: usize,
    },
    /// A NatNet 4.1+ section or description size disagrees with its content.
    #[error("section at byte {offset} announces {declared} bytes, its content takes {actual}")]
    SectionSize {
        /// Offset of the size field.
        offset: usize,
        /// Size in the field.
        declared: usize,
        /// Bytes the content actually took.
        actual: usize,
    },
    /// The NatNet version is not one this decoder supports (3.0 to 4.x).
    #[error("natnet version {major}.{minor} is not supported")]
    UnsupportedVersion {
        /// Major version.
        major: u8,
        /// Minor version.
        minor: u8,
    },
    /// The message id is not a NatNet message id.
    #[error("unknown message id {id}")]
    UnknownMessage {
        /// The id as sent.
        id: u16,
    },
    /// A known message, but not the one this decoder handles.
    #[error("expected message id {expected}, got {got}")]
    WrongMessage {
        /// The id this decoder handles.
        expected: u16,
        /// The id in the header.
        got: u16,
    },
    /// A float that must be a number is infinite (or NaN where NaN has no meaning).
    #[error("non-finite value at byte {offset}")]
    NonFinite {
        /// Offset of the value.
        offset: usize,
    },
    /// A string has no NUL terminator in the payload, or is not UTF-8.
    #[error("bad string at byte {offset}")]
    BadString {
        /// Offset of the string.
        offset: usize,
    },
    /// A data description type this decoder does not know and cannot skip (before 4.1).
    #[error("unknown data description type {type_id} at byte {offset}")]
    UnknownDescription {
        /// The type as sent.
        type_id: i32,
        /// Offset of the type field.
        offset: usize,
    },
}

/// Field-less twin of [`NatNetError`], for counters keyed by kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[allow(missing_docs)] // each variant mirrors the NatNetError variant of the same name
pub enum NatNetErrorKind {
    Truncated,
    TrailingBytes,
    PayloadSize,
    BadCount,
    SectionSize,
    UnsupportedVersion,
    UnknownMessage,
    WrongMessage,
    NonFinite,
    BadString,
    UnknownDescription,
}

impl NatNetErrorKind {
    /// Every kind, in declaration order: `ALL[k.index()] == k`.
    pub const ALL: [NatNetErrorKind; 11] = [
        Self::Truncated,
        Self::TrailingBytes,
        Self::PayloadSize,
        Self::BadCount,
        Self::SectionSize,
        Self::UnsupportedVersion,
        Self::UnknownMessage,
        Self::WrongMessage,
        Self::NonFinite,
        Self::BadString,
        Self::UnknownDescription,
    ];

    /// Dense index for an array of counters (`[u64; NatNetErrorKind::ALL.len()]`).
    pub fn index(self) -> usize {
        self as usize
    }

    /// Stable snake_case name, for status replies and logs.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Truncated => "natnet_truncated",
            Self::TrailingBytes => "natnet_trailing_bytes",
            Self::PayloadSize => "natnet_payload_size",
            Self::BadCount => "natnet_bad_count",
            Self::SectionSize => "natnet_section_size",
            Self::UnsupportedVersion => "natnet_unsupported_version",
            Self::UnknownMessage => "natnet_unknown_message",
            Self::WrongMessage => "natnet_wrong_message",
            Self::NonFinite => "natnet_non_finite",
            Self::BadString => "natnet_bad_string",
            Self::UnknownDescription => "natnet_unknown_description",
        }
    }
}

impl NatNetError {
    /// The kind of this error, for counters.
    pub fn kind(self) -> NatNetErrorKind {
        use NatNetErrorKind as K;
        match self {
            Self::Truncated { .. } => K::Truncated,
            Self::TrailingBytes { .. } => K::TrailingBytes,
            Self::PayloadSize { .. } => K::PayloadSize,
            Self::BadCount { .. } => K::BadCount,
            Self::SectionSize { .. } => K::SectionSize,
            Self::UnsupportedVersion { .. } => K::UnsupportedVersion,
            Self::UnknownMessage { .. } => K::UnknownMessage,
            Self::WrongMessage { .. } => K::WrongMessage,
            Self::NonFinite { .. } => K::NonFinite,
            Self::BadString { .. } => K::BadString,
            Self::UnknownDescription { .. } => K::UnknownDescription,
        }
    }
}

/// Why a NAT_MODELDEF could not be decoded: the low-level error and where it happened.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ModelDefError {
    /// The packet framing or the description count is wrong.
    #[error("model definitions: {0}")]
    Packet(#[source] NatNetError),
    /// Description `index` (of type `type_id`) is malformed.
    #[error("data description {index} (type {type_id}): {source}")]
    Description {
        /// Position of the description in the packet, from 0.
        index: usize,
        /// Its type (0 markerset, 1 rigid body, 2 skeleton, 3 force plate, 4 device, 5 camera,
        /// 6 asset).
        type_id: i32,
        /// What was wrong.
        #[source]
        source: NatNetError,
    },
}

/// Why a NatNet message could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum NatNetEncodeError {
    /// The payload would not fit the header's 16-bit size field.
    #[error("payload of {len} bytes exceeds the maximum of {max}")]
    Oversize {
        /// Payload length.
        len: usize,
        /// The limit (65,535).
        max: usize,
    },
    /// A string contains a NUL byte, which NatNet strings cannot carry.
    #[error("string contains a nul byte")]
    NulInString,
    /// A fixed-size string field is too small for the string and its terminator.
    #[error("string of {len} bytes does not fit a field of {max}")]
    StringTooLong {
        /// String length in bytes.
        len: usize,
        /// Field size including the terminator.
        max: usize,
    },
    /// A count does not fit the wire's `i32`.
    #[error("count {count} does not fit an i32")]
    CountOverflow {
        /// The count.
        count: usize,
    },
    /// The version has no layout this encoder writes (before 3.0, or after 4.x).
    #[error("natnet version {major}.{minor} cannot be encoded")]
    UnsupportedVersion {
        /// Major version.
        major: u8,
        /// Minor version.
        minor: u8,
    },
}

#[cfg(test)]
mod tests;
