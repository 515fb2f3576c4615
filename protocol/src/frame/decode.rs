//! Decoding `/mocap/frame` into a [`FrameBuf`] without allocating: blob form (`,ihbb`) and
//! flat form (`,ih` + `f`*).

use super::{all_finite, FrameBuf, FrameForm, FrameHeader};
use crate::address::FRAME;
use crate::error::DecodeError;
use crate::scan::read_head;
use crate::wire::Reader;

/// Decodes one `/mocap/frame` message (either form) into `buf`, without allocating.
///
/// `msg` is one message: a bare datagram or a [`crate::Message::bytes`] from [`crate::messages`]
/// (frames inside bundles). The parse is complete and strict on its own; no pre-scan is needed.
/// On error the buffer's contents are unspecified (its capacity is kept).
///
/// # Errors
/// [`DecodeError::UnknownAddress`] for another address; [`DecodeError::WrongTypeTags`] for
/// tags other than `,ihbb` or `,ih` + `f`*; [`DecodeError::WrongCount`] for positions not a
/// multiple of 12 bytes (3 floats), a mask of the wrong length, or mask bits set past the last
/// marker; [`DecodeError::NonFinite`] for NaN/Inf in a present marker (blob form) or Inf (flat
/// form); [`DecodeError::PartlyMissing`]; [`DecodeError::TooManyMarkers`]; truncation and
/// trailing bytes.
pub fn decode_frame_into(msg: &[u8], buf: &mut FrameBuf) -> Result<FrameHeader, DecodeError> {
    let (address, tags, mut r) = read_head(msg)?;
    if address != FRAME {
        return Err(DecodeError::UnknownAddress);
    }
    match tags {
        b"ihbb" => decode_blob_form(&mut r, buf)?,
        [b'i', b'h', floats @ ..] if floats.iter().all(|&t| t == b'f') => {
            decode_flat_form(&mut r, floats.len(), buf)?
        }
        _ => return Err(DecodeError::WrongTypeTags),
    }
    if r.remaining() != 0 {
        return Err(DecodeError::TrailingBytes {
            offset: r.pos(),
            extra: r.remaining(),
        });
    }
    Ok(buf.header)
}

fn decode_blob_form(r: &mut Reader<'_>, buf: &mut FrameBuf) -> Result<(), DecodeError> {
    let frame_number = r.i32()?;
    let capture_time_us = r.i64()?;
    let mask = r.blob()?;
    let coords = r.blob()?;
    if coords.len() % 12 != 0 {
        return Err(DecodeError::WrongCount {
            expected: coords.len() / 12 * 12,
            got: coords.len(),
        });
    }
    let n = coords.len() / 12;
    if mask.len() != n.div_ceil(8) {
        return Err(DecodeError::WrongCount {
            expected: n.div_ceil(8),
            got: mask.len(),
        });
    }
    // bits past the last marker must be clear, or a sender disagrees with us on the count
    if n % 8 != 0 && mask.last().is_some_and(|&b| b >> (n % 8) != 0) {
        return Err(DecodeError::WrongCount {
            expected: n,
            got: mask.len() * 8,
        });
    }
    buf.reset_empty(n, FrameForm::Blob)?;
    buf.set_header(frame_number, capture_time_us);
    buf.missing.extend_from_slice(mask);
    // convert every coordinate in one tight loop (it vectorises), then fix up and validate
    be_f32s_into(coords, &mut buf.positions);
    let all_present = mask.iter().all(|&b| b == 0);
    if all_present && all_finite(&buf.positions) {
        return Ok(());
    }
    let mut missing = 0;
    for (m, xyz) in buf.positions.chunks_exact_mut(3).enumerate() {
        if mask[m / 8] >> (m % 8) & 1 == 1 {
            xyz.fill(f32::NAN);
            missing += 1;
        } else if !xyz.iter().all(|v| v.is_finite()) {
            return Err(DecodeError::NonFinite { marker: m });
        }
    }
    buf.header.missing_count = missing;
    Ok(())
}

fn decode_flat_form(
    r: &mut Reader<'_>,
    floats: usize,
    buf: &mut FrameBuf,
) -> Result<(), DecodeError> {
    if floats % 3 != 0 {
        return Err(DecodeError::WrongCount {
            expected: floats / 3 * 3,
            got: floats,
        });
    }
    let frame_number = r.i32()?;
    let capture_time_us = r.i64()?;
    let coords = r.take(floats * 4)?;
    let n = floats / 3;
    buf.reset_empty(n, FrameForm::Flat)?;
    buf.set_header(frame_number, capture_time_us);
    buf.missing.resize(n.div_ceil(8), 0);
    be_f32s_into(coords, &mut buf.positions);
    if all_finite(&buf.positions) {
        return Ok(());
    }
    for m in 0..n {
        let xyz = &buf.positions[3 * m..3 * m + 3];
        match xyz.iter().filter(|v| v.is_nan()).count() {
            0 if xyz.iter().all(|v| v.is_finite()) => {}
            0 => return Err(DecodeError::NonFinite { marker: m }),
            3 => {
                buf.missing[m / 8] |= 1 << (m % 8);
                buf.header.missing_count += 1;
            }
            _ => return Err(DecodeError::PartlyMissing { marker: m }),
        }
    }
    Ok(())
}

/// Appends big-endian f32s (`bytes.len()` a multiple of 4) to `out`, within its capacity.
fn be_f32s_into(bytes: &[u8], out: &mut Vec<f32>) {
    let at = out.len();
    out.resize(at + bytes.len() / 4, 0.0);
    for (d, c) in out[at..].iter_mut().zip(bytes.chunks_exact(4)) {
        *d = f32::from_be_bytes([c[0], c[1], c[2], c[3]]);
    }
}
