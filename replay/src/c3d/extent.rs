//! How far a C3D file's data runs against its header, and the in-place patch that makes the
//! header count what the data holds.
//!
//! A recording cut off by a crash (SIGKILL, a power cut) holds more frames than its header
//! last counted, and may end inside a frame. A finished file ends on a block boundary, its
//! last block padded after the header's frames; writers leave anything in that padding (the
//! c3d.org samples hold stale records and half records there), so a file that ends on a block
//! boundary no later than the header's frames padded holds nothing more. Past that, frames are
//! data if any of their bytes is not zero: a recording never writes an all-zero record (a
//! missing sample's residual word is -1), and a power cut can leave a zero tail.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};

use super::binary::{Processor, BLOCK};
use super::frames::read_head;
use super::layout::Layout;
use super::params::{Param, Params, Value};
use crate::error::ReadError;

/// Why [`patch`] could not make the header count the frames (the repair module's
/// `RepairError` gives each its message).
#[derive(Debug)]
pub(crate) enum PatchError {
    /// No frame to count.
    NoFrames,
    /// A range past the header's 16-bit last frame, and no TRIAL:ACTUAL_END_FIELD.
    NoRoom {
        /// First frame.
        first: i64,
        /// Last frame.
        last: i64,
    },
    /// An I/O error.
    Io(std::io::Error),
}

impl From<std::io::Error> for PatchError {
    fn from(e: std::io::Error) -> PatchError {
        PatchError::Io(e)
    }
}

/// Byte offset of the header's last-frame word.
const HEADER_LAST_FRAME: u64 = 8;

/// What a C3D file's header counts and what its data holds.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Extent {
    /// Frames the header's range counts.
    pub(crate) header_frames: usize,
    /// Whole frames of data (trailing all-zero records past the header's count left out).
    pub(crate) data_frames: usize,
    /// Bytes after the last whole frame that are not zero: a frame cut off mid-write.
    pub(crate) torn_bytes: u64,
    first_frame: i64,
    processor: Processor,
    data_offset: u64,
    frame_bytes: u64,
    /// POINT:FRAMES, POINT:LONG_FRAMES and TRIAL:ACTUAL_END_FIELD, where the file has them.
    fields: [Option<Param>; 3],
}

/// Reads the header and parameters of `file` and measures its data.
///
/// # Errors
/// A header or parameter section the readers refuse, or an I/O error.
pub(crate) fn measure(file: &mut File) -> Result<Extent, ReadError> {
    let len = file.metadata()?.len();
    file.seek(SeekFrom::Start(0))?;
    let head = read_head(file)?;
    // Unlimited length: the data is measured here, not checked against the header.
    let layout = Layout::new(head.processor, &head.header, &head.params, usize::MAX)?;
    let data_offset = layout.data_offset as u64;
    let frame_bytes = layout.frame_bytes() as u64;
    let available = len.saturating_sub(data_offset);
    let whole = available / frame_bytes;
    let header_frames = layout.frames as u64;
    let block = BLOCK as u64;
    let padded_end = (data_offset + header_frames * frame_bytes).div_ceil(block) * block;
    let field = |params: &Params, group: &str, name: &str| params.get(group, name).cloned();
    let mut extent = Extent {
        header_frames: layout.frames,
        data_frames: layout.frames,
        torn_bytes: 0,
        first_frame: layout.first_frame,
        processor: head.processor,
        data_offset,
        frame_bytes,
        fields: [
            field(&head.params, "POINT", "FRAMES"),
            field(&head.params, "POINT", "LONG_FRAMES"),
            field(&head.params, "TRIAL", "ACTUAL_END_FIELD"),
        ],
    };
    if len % block == 0 && len <= padded_end {
        // A finished file: what follows the header's frames is its padding.
        extent.data_frames = usize::try_from(whole.min(header_frames)).unwrap_or(usize::MAX);
        return Ok(extent);
    }
    let mut frames = whole;
    let mut record = vec![0u8; layout.frame_bytes()];
    let floor = header_frames.min(whole);
    while frames > floor {
        file.seek(SeekFrom::Start(data_offset + (frames - 1) * frame_bytes))?;
        file.read_exact(&mut record)?;
        if record.iter().any(|&b| b != 0) {
            break;
        }
        frames -= 1;
    }
    let tail = available % frame_bytes;
    let mut rest = vec![0u8; tail as usize];
    file.seek(SeekFrom::Start(data_offset + whole * frame_bytes))?;
    file.read_exact(&mut rest)?;
    if rest.iter().any(|&b| b != 0) {
        extent.torn_bytes = tail;
    }
    extent.data_frames = usize::try_from(frames).unwrap_or(usize::MAX);
    Ok(extent)
}

/// Makes the header of `file` count `frames` frames: the header's last frame, POINT:FRAMES,
/// POINT:LONG_FRAMES and TRIAL:ACTUAL_END_FIELD where present, each in place; the data cut
/// after the last of them and padded with zeros to a whole block.
///
/// # Errors
/// [`PatchError::NoFrames`], [`PatchError::NoRoom`] or an I/O error.
pub(crate) fn patch(file: &mut File, e: &Extent, frames: usize) -> Result<(), PatchError> {
    if frames == 0 {
        return Err(PatchError::NoFrames);
    }
    // As stored: a take whose first frame is past 65535 is numbered from 1 in the header and
    // TRIAL (its true first frame in EMOSHIFT:FIRST_FRAME, which does not change).
    let first = if e.first_frame > i64::from(u16::MAX) {
        1
    } else {
        e.first_frame
    };
    let last = first + frames as i64 - 1;
    let long = frames > usize::from(u16::MAX) || last > i64::from(u16::MAX);
    let [point_frames, long_frames, end_field] = &e.fields;
    if long && end_field.is_none() {
        return Err(PatchError::NoRoom { first, last });
    }
    let p = e.processor;
    let saturated = |v: i64| u16::try_from(v).unwrap_or(u16::MAX);
    put(file, HEADER_LAST_FRAME, &p.put_u16(saturated(last)))?;
    if let Some(param) = point_frames {
        put_number(file, p, param, 0, f64::from(saturated(frames as i64)))?;
    }
    if let Some(param) = long_frames {
        put_number(file, p, param, 0, frames as f64)?;
    }
    if let Some(param) = end_field {
        put_number(file, p, param, 0, (last & 0xFFFF) as f64)?;
        put_number(file, p, param, 1, (last >> 16) as f64)?;
    }
    let end = e.data_offset + frames as u64 * e.frame_bytes;
    file.set_len(end)?;
    // Zero padding to a whole block, as the writer leaves it: some readers expect it.
    file.set_len(end.div_ceil(BLOCK as u64) * BLOCK as u64)?;
    file.sync_all()?;
    Ok(())
}

/// Writes `bytes` at `at`.
fn put(file: &mut File, at: u64, bytes: &[u8]) -> std::io::Result<()> {
    file.seek(SeekFrom::Start(at))?;
    file.write_all(bytes)
}

/// Writes value `index` of a numeric parameter in its own type (integers as 16-bit words,
/// unsigned where they count); a value the parameter has no room for is skipped.
fn put_number(
    file: &mut File,
    p: Processor,
    param: &Param,
    index: usize,
    v: f64,
) -> std::io::Result<()> {
    let at = param.offset as u64;
    match &param.value {
        Value::Int(values) if index < values.len() => {
            put(file, at + 2 * index as u64, &p.put_u16(v as u16))
        }
        Value::Float(values) if index < values.len() => {
            put(file, at + 4 * index as u64, &p.put_f32(v as f32))
        }
        Value::Byte(values) if index < values.len() => put(file, at + index as u64, &[v as u8]),
        _ => Ok(()),
    }
}
