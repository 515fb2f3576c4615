//! What can be wrong with a C3D file, and what a take may hold that C3D cannot.

/// Why a C3D file could not be read. Each message names the bad value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum C3dError {
    /// Shorter than the 512-byte header.
    #[error("c3d file is {len} bytes, shorter than the 512-byte header")]
    TooShort {
        /// File length in bytes.
        len: usize,
    },
    /// The second byte is not the C3D signature 0x50.
    #[error("not a c3d file: header byte 2 is {byte:#04x}, expected 0x50")]
    NotC3d {
        /// The byte found.
        byte: u8,
    },
    /// The header points at a parameter block that is not in the file.
    #[error("c3d parameter section starts at block {block}, but the file has {blocks} blocks")]
    ParameterBlockOutside {
        /// 1-based block number from the header.
        block: usize,
        /// Whole blocks in the file.
        blocks: usize,
    },
    /// The parameter section names no known processor.
    #[error("c3d processor type is {byte}, expected 84 (intel), 85 (dec) or 86 (mips)")]
    UnknownProcessor {
        /// The processor byte.
        byte: u8,
    },
    /// A parameter record is malformed.
    #[error("c3d parameter section is corrupt at byte {offset}: {reason}")]
    BadParameters {
        /// Absolute byte offset of the record.
        offset: usize,
        /// What is wrong.
        reason: &'static str,
    },
    /// The file declares no 3D points.
    #[error("c3d file holds no 3d points (POINT:USED and header point count are 0)")]
    NoPoints,
    /// POINT:USED disagrees with the header point count.
    #[error("c3d POINT:USED is {used} but the header says {header} points")]
    PointCountMismatch {
        /// POINT:USED.
        used: usize,
        /// Header word 2.
        header: usize,
    },
    /// The header's frame range is empty.
    #[error("c3d header frame range {first}..{last} is empty")]
    BadFrameRange {
        /// First frame.
        first: i64,
        /// Last frame.
        last: i64,
    },
    /// POINT:FRAMES disagrees with the header's frame range.
    #[error("c3d POINT:FRAMES is {parameter} but the header frame range {first}..{last} holds {header} frames")]
    FrameCountMismatch {
        /// POINT:FRAMES.
        parameter: usize,
        /// Frames in the header range.
        header: usize,
        /// First frame.
        first: i64,
        /// Last frame.
        last: i64,
    },
    /// The header and POINT:DATA_START give no usable data block.
    #[error("c3d data start block {block} is invalid (parameter section starts at block {parameter_block})")]
    BadDataStart {
        /// The data block used.
        block: usize,
        /// The parameter block.
        parameter_block: usize,
    },
    /// The data section ends before the last frame.
    #[error("c3d data is truncated: frames {first}..{last} need {needed} bytes after block {data_block}, file has {available}")]
    Truncated {
        /// First frame.
        first: i64,
        /// Last frame.
        last: i64,
        /// Bytes needed.
        needed: usize,
        /// Bytes present.
        available: usize,
        /// 1-based data start block.
        data_block: usize,
    },
    /// The frame rate is not a positive finite number.
    #[error("c3d frame rate {0} Hz is not a positive finite number")]
    BadRate(f32),
    /// The point scale is zero or not finite.
    #[error("c3d point scale {0} is zero or not finite")]
    BadScale(f32),
}

/// Why a take cannot be written as C3D.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum C3dLimitError {
    /// More markers than POINT:USED (a signed 16-bit word) can count.
    #[error("c3d holds at most {max} markers, take has {markers}")]
    TooManyMarkers {
        /// Markers in the take.
        markers: usize,
        /// The limit.
        max: usize,
    },
    /// A label longer than a C3D string dimension (one byte) allows.
    #[error("c3d labels are at most 255 bytes, {label:?} has {len}")]
    LabelTooLong {
        /// The label.
        label: String,
        /// Its length in bytes.
        len: usize,
    },
    /// A negative first frame number (C3D numbers frames from 0 up).
    #[error("c3d frame numbers cannot be negative, take starts at {0}: write TRC or CSV, or renumber the take")]
    FirstFrameOutOfRange(i64),
    /// More frames than the TRIAL:ACTUAL_END_FIELD pair of words can count.
    #[error("c3d frame range {first}..{last} does not fit in 32 bits")]
    TooManyFrames {
        /// First frame.
        first: i64,
        /// Last frame.
        last: i64,
    },
    /// A take with no frames: the header's frame range cannot be empty.
    #[error("c3d needs at least one frame, take has none")]
    NoFrames,
    /// The parameter section would exceed the 255 blocks its one-byte count allows.
    #[error("c3d parameter section would need {blocks} blocks, at most 255 fit")]
    TooManyParameterBlocks {
        /// Blocks needed.
        blocks: usize,
    },
}
