//! Encoding a [`FrameBuf`] as `/mocap/frame`, blob form or flat form.

use super::{all_finite, FrameBuf};
use crate::address::FRAME;
use crate::error::EncodeError;
use crate::wire;

/// Bytes of a `,ihbb` frame message with `markers` markers (1,368 for 109).
pub const fn frame_message_len(markers: usize) -> usize {
    16 + 8 + 4 + 8 + 4 + wire::pad4(markers.div_ceil(8)) + 4 + 12 * markers
}

/// Encodes `frame` as `/mocap/frame ,ihbb` into `out` (cleared first, capacity reused).
/// Missing markers are written as NaN. Returns the encoded length.
///
/// # Errors
/// [`EncodeError::NonFinite`] if a present marker holds NaN or Inf.
pub fn encode_frame_into(frame: &FrameBuf, out: &mut Vec<u8>) -> Result<usize, EncodeError> {
    out.clear();
    append_frame(frame, out)?;
    Ok(out.len())
}

/// Appends the `,ihbb` message (used alone and inside the compact bundle).
pub(crate) fn append_frame(frame: &FrameBuf, out: &mut Vec<u8>) -> Result<(), EncodeError> {
    let h = frame.header;
    let start = out.len();
    wire::put_str_unchecked(out, FRAME);
    wire::put_str_unchecked(out, ",ihbb");
    wire::put_i32(out, h.frame_number);
    wire::put_i64(out, h.capture_time_us);
    wire::put_blob_len(out, frame.missing.len());
    out.extend_from_slice(&frame.missing);
    wire::pad_to4(out, start);
    wire::put_blob_len(out, frame.positions.len() * 4);
    let coords_at = out.len();
    out.resize(coords_at + frame.positions.len() * 4, 0);
    // a zip over pre-sized slices: no capacity checks in the loop, so it vectorises
    for (c, v) in out[coords_at..].chunks_exact_mut(4).zip(&frame.positions) {
        c.copy_from_slice(&v.to_be_bytes());
    }
    // missing markers go out as NaN whatever an edit wrote into them
    if frame.header.missing_count > 0 {
        for (k, &byte) in frame.missing.iter().enumerate().filter(|(_, &b)| b != 0) {
            for bit in (0..8).filter(|bit| byte >> bit & 1 == 1) {
                let at = coords_at + 12 * (8 * k + bit);
                for c in out[at..at + 12].chunks_exact_mut(4) {
                    c.copy_from_slice(&f32::NAN.to_be_bytes());
                }
            }
        }
    }
    if !all_finite(&frame.positions) {
        let bad = frame
            .positions
            .chunks_exact(3)
            .enumerate()
            .find(|(m, xyz)| !frame.is_missing(*m) && !xyz.iter().all(|v| v.is_finite()));
        if let Some((marker, _)) = bad {
            out.truncate(start);
            return Err(EncodeError::NonFinite { marker });
        }
    }
    Ok(())
}

/// Encodes `frame` in the flat form `/mocap/frame ,ih f...` (NaN for missing markers), for
/// sources and tests that speak it. Returns the encoded length.
///
/// # Errors
/// [`EncodeError::NonFinite`] if a present marker holds NaN or Inf.
pub fn encode_frame_flat_into(frame: &FrameBuf, out: &mut Vec<u8>) -> Result<usize, EncodeError> {
    out.clear();
    let h = frame.header;
    wire::put_prologue(out, 0, FRAME, b"ih", b'f', frame.positions.len());
    wire::put_i32(out, h.frame_number);
    wire::put_i64(out, h.capture_time_us);
    for (m, xyz) in frame.positions.chunks_exact(3).enumerate() {
        let missing = frame.is_missing(m);
        if !missing && !xyz.iter().all(|v| v.is_finite()) {
            out.clear();
            return Err(EncodeError::NonFinite { marker: m });
        }
        for &v in xyz {
            wire::put_f32(out, if missing { f32::NAN } else { v });
        }
    }
    Ok(out.len())
}
