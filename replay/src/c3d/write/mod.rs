//! The C3D writer: Intel float32, the parameter groups strict readers (ezc3d, py-c3d) require.

use std::io::Write;

use super::binary::{BLOCK, SIGNATURE};
use crate::error::c3d::C3dLimitError;
use crate::error::WriteError;
use crate::Take;

/// Processor byte for Intel (83 + 1).
const INTEL: u8 = 84;
/// POINT:SCALE. Negative flags float32 storage; magnitude 1 so readers that multiply float
/// values by |scale| anyway (py-c3d does for int16 only, some older tools always) get the same
/// numbers, and residuals stay in millimetres.
const SCALE: f32 = -1.0;
/// Residual word of a missing sample: -1 is the C3D "invalid" flag.
const MISSING_WORD: f32 = -1.0;
/// Residual word of a present sample: no residual or camera information recorded.
const PRESENT_WORD: f32 = 0.0;
/// Strings per LABELS / DESCRIPTIONS parameter: a dimension is one byte.
const LABELS_PER_PARAM: usize = 255;
/// Markers POINT:USED (a signed 16-bit word) can count.
const MAX_MARKERS: usize = i16::MAX as usize;
/// The parameter section's block count is one byte.
const MAX_PARAMETER_BLOCKS: usize = 255;

/// Writes a take as C3D: Intel, float32 points (POINT:SCALE -1), millimetres.
///
/// Groups: POINT (USED, FRAMES, DATA_START, SCALE, RATE, UNITS "mm", LABELS and DESCRIPTIONS,
/// continued by LABELS2... past 255 markers), an empty ANALOG group (USED 0) and FORCE_PLATFORM
/// (USED 0), and TRIAL:ACTUAL_START_FIELD / ACTUAL_END_FIELD holding the true frame range as
/// (low, high) 16-bit words. Takes longer than the header's 16-bit last frame allows are written
/// as Vicon does: header last frame and POINT:FRAMES 65535, real count in POINT:LONG_FRAMES and
/// TRIAL. A missing sample is xyz 0 with residual word -1. A present sample that is exactly
/// (0, 0, 0) will read back as missing (C3D has no way to say otherwise).
///
/// # Errors
/// [`WriteError::Invalid`] for a take that breaks its invariants, [`WriteError::C3dLimit`] for
/// one C3D cannot hold (no frames, too many markers, a label over 255 bytes, a negative first
/// frame), or an I/O error.
pub fn write(take: &Take, out: &mut impl Write) -> Result<(), WriteError> {
    take.validate()?;
    let frames = take.n_frames();
    write_head(out, &take.labels, (take.rate_hz, take.first_frame), frames)?;
    write_frames(out, take, &mut Vec::new())?;
    write_padding(out, frames, take.n_markers())
}

/// Header and parameter section of a take of `frames` frames: everything before the first
/// frame.
///
/// # Errors
/// What C3D cannot hold (no frames, too many markers, a long label, a negative first frame),
/// or an I/O error.
pub(crate) fn write_head(
    out: &mut impl Write,
    labels: &[String],
    (rate_hz, first_frame): (f64, i64),
    frames: usize,
) -> Result<(), WriteError> {
    let range = FrameRange::new(first_frame, frames)?;
    check_labels(labels)?;
    let meta = Meta {
        labels,
        rate_hz,
        time: None,
    };
    let blocks = parameter_blocks(&meta, &range)?;
    out.write_all(&head(&meta, &range, blocks))?;
    Ok(())
}

/// Every frame of `take` as records, `buf` reused.
///
/// # Errors
/// An I/O error.
pub(crate) fn write_frames(
    out: &mut impl Write,
    take: &Take,
    buf: &mut Vec<u8>,
) -> std::io::Result<()> {
    for f in 0..take.n_frames() {
        encode_frame(take.frame(f), take.frame_missing(f), buf);
        out.write_all(buf)?;
    }
    Ok(())
}

/// The zero padding after the last of `frames` frames.
///
/// # Errors
/// An I/O error.
pub(crate) fn write_padding(
    out: &mut impl Write,
    frames: usize,
    markers: usize,
) -> Result<(), WriteError> {
    out.write_all(&vec![0u8; padding(frames, markers)])?;
    Ok(())
}

/// What the header and parameters say about the points, besides the frame range.
pub(crate) struct Meta<'a> {
    /// Marker labels.
    pub(crate) labels: &'a [String],
    /// Frame rate, Hz.
    pub(crate) rate_hz: f64,
    /// A recording's timecode and measured rate.
    pub(crate) time: Option<&'a crate::take::RecordTime>,
}

/// Rejects labels C3D cannot hold: too many markers, a label over 255 bytes.
pub(crate) fn check_labels(labels: &[String]) -> Result<(), C3dLimitError> {
    if labels.len() > MAX_MARKERS {
        return Err(C3dLimitError::TooManyMarkers {
            markers: labels.len(),
            max: MAX_MARKERS,
        });
    }
    if let Some(l) = labels.iter().find(|l| l.len() > 255) {
        return Err(C3dLimitError::LabelTooLong {
            label: l.clone(),
            len: l.len(),
        });
    }
    Ok(())
}

/// Blocks the parameter section of `range` needs.
///
/// # Errors
/// [`C3dLimitError::TooManyParameterBlocks`] past the one-byte block count.
pub(crate) fn parameter_blocks(
    meta: &Meta<'_>,
    range: &FrameRange,
) -> Result<usize, C3dLimitError> {
    // The data block depends on the parameter size, which depends on DATA_START's value only
    // through its fixed width: measure with a placeholder.
    let blocks = parameters(meta, range, 0).len().div_ceil(BLOCK);
    if blocks > MAX_PARAMETER_BLOCKS {
        return Err(C3dLimitError::TooManyParameterBlocks { blocks });
    }
    Ok(blocks)
}

/// The header block and a parameter section padded to `blocks` blocks (at least what
/// [`parameter_blocks`] reports for `range`): everything before the first frame. A recorder
/// reserves the blocks of the longest range up front and rewrites this in place on finish.
pub(crate) fn head(meta: &Meta<'_>, range: &FrameRange, blocks: usize) -> Vec<u8> {
    let data_block = (2 + blocks) as u16;
    let mut bytes = header(meta, range, data_block).to_vec();
    let mut params = parameters(meta, range, data_block);
    debug_assert!(
        params.len() <= blocks * BLOCK,
        "caller reserved enough blocks"
    );
    params.resize(blocks * BLOCK, 0);
    params[2] = blocks as u8;
    bytes.extend_from_slice(&params);
    bytes
}

/// Zero bytes that pad the data of `frames` frames to whole blocks: some readers expect them.
pub(crate) fn padding(frames: usize, markers: usize) -> usize {
    let data_len = frames * markers * 16;
    (BLOCK - data_len % BLOCK) % BLOCK
}

/// Encodes one frame (markers x 3 mm, one missing flag per marker) into `buf`, cleared first:
/// x y z and a residual word per marker, a missing marker as xyz 0 with residual -1.
pub(crate) fn encode_frame(xyz: &[f32], missing: &[bool], buf: &mut Vec<u8>) {
    buf.clear();
    for (p, &gone) in xyz.chunks_exact(3).zip(missing) {
        if gone {
            buf.extend_from_slice(&[0u8; 12]);
            buf.extend_from_slice(&MISSING_WORD.to_le_bytes());
        } else {
            for v in p {
                buf.extend_from_slice(&v.to_le_bytes());
            }
            buf.extend_from_slice(&PRESENT_WORD.to_le_bytes());
        }
    }
}

/// The frame numbers as the header and TRIAL store them.
///
/// The header's first frame is a 16-bit word. A take whose first frame is past 65535 (a live
/// source's numbers, e.g. Motive's after nine minutes at 120 Hz) is stored numbered from 1,
/// in the header and TRIAL alike, so every reader counts its frames right; its true first frame
/// goes in EMOSHIFT:FIRST_FRAME, which emoshift's reader applies.
pub(crate) struct FrameRange {
    /// The first and last frame as stored (numbered from 1 when renumbered).
    first: u32,
    last: u32,
    count: usize,
    /// The true first frame of a renumbered take.
    renumbered_from: Option<u32>,
}

impl FrameRange {
    /// The range of `frames` frames numbered from `first_frame`.
    ///
    /// # Errors
    /// No frames, a negative first frame, a last frame past 32 bits.
    pub(crate) fn new(first_frame: i64, frames: usize) -> Result<FrameRange, C3dLimitError> {
        if frames == 0 {
            return Err(C3dLimitError::NoFrames);
        }
        let true_first = u32::try_from(first_frame)
            .map_err(|_| C3dLimitError::FirstFrameOutOfRange(first_frame))?;
        let last = first_frame + frames as i64 - 1;
        if u32::try_from(last).is_err() {
            return Err(C3dLimitError::TooManyFrames {
                first: first_frame,
                last,
            });
        }
        let renumbered_from = (true_first > u32::from(u16::MAX)).then_some(true_first);
        let first = if renumbered_from.is_some() {
            1
        } else {
            true_first
        };
        let last = u32::try_from(i64::from(first) + frames as i64 - 1).map_err(|_| {
            C3dLimitError::TooManyFrames {
                first: first_frame,
                last,
            }
        })?;
        Ok(FrameRange {
            first,
            last,
            count: frames,
            renumbered_from,
        })
    }

    /// A range long enough to need POINT:LONG_FRAMES: the parameter section a recorder
    /// reserves, since it cannot know its length up front and longer ranges need no more room.
    pub(crate) fn longest(first_frame: i64) -> Result<FrameRange, C3dLimitError> {
        FrameRange::new(first_frame, usize::from(u16::MAX) + 1)
    }

    /// The header's last frame, saturated at 65535.
    fn header_last(&self) -> u16 {
        u16::try_from(self.last).unwrap_or(u16::MAX)
    }

    /// POINT:FRAMES, saturated at 65535 (stored as the bit pattern of a signed word).
    fn point_frames(&self) -> u16 {
        u16::try_from(self.count).unwrap_or(u16::MAX)
    }

    fn long(&self) -> bool {
        self.count > usize::from(u16::MAX) || self.last > u32::from(u16::MAX)
    }
}

fn header(meta: &Meta<'_>, range: &FrameRange, data_block: u16) -> [u8; BLOCK] {
    let mut h = [0u8; BLOCK];
    h[0] = 2;
    h[1] = SIGNATURE;
    let mut put = |at: usize, b: &[u8]| h[at..at + b.len()].copy_from_slice(b);
    put(2, &(meta.labels.len() as u16).to_le_bytes());
    put(4, &0u16.to_le_bytes()); // analog samples per frame
    put(6, &(range.first as u16).to_le_bytes());
    put(8, &range.header_last().to_le_bytes());
    put(10, &0u16.to_le_bytes()); // maximum interpolation gap
    put(12, &SCALE.to_le_bytes());
    put(16, &data_block.to_le_bytes());
    // Analog samples per channel per frame: 1, matching ANALOG:RATE = POINT:RATE (py-c3d checks
    // that this word equals their ratio even with no analog channels).
    put(18, &1u16.to_le_bytes());
    put(20, &(meta.rate_hz as f32).to_le_bytes());
    h
}

mod params;
mod records;
mod timecode;

use params::parameters;
#[cfg(test)]
use records::Records;

#[cfg(test)]
mod tests;
