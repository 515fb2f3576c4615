//! Decoders of the output profiles, for clients and tests: `/mocap/part`,
//! `/emoshift/components`, `/emoshift/state` and `/VMC/Ext/Blend/Val`. Borrowed, no allocation.

use crate::address::{COMPONENTS, PART, STATE, VMC_BLEND_VAL};
use crate::error::DecodeError;
use crate::scan::read_head;

/// Header of a decoded `/mocap/part`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PartHeader {
    /// Frame number.
    pub frame_number: i32,
    /// Index of the first marker in this part.
    pub first_marker: usize,
    /// Markers in this part.
    pub marker_count: usize,
    /// Markers in the whole frame.
    pub total_markers: usize,
}

/// Decodes a `/mocap/part` into `positions[3 * first .. 3 * (first + count)]` (a frame-sized
/// caller buffer), without allocating. NaN coordinates (missing markers) are kept.
///
/// # Errors
/// [`DecodeError::WrongTypeTags`], [`DecodeError::WrongCount`] (float count vs marker count),
/// [`DecodeError::OutOfRange`] (negative or inconsistent indices),
/// [`DecodeError::TooManyMarkers`] (frame larger than `positions`), [`DecodeError::NonFinite`]
/// (infinite coordinate), truncation and trailing bytes.
pub fn decode_part_into(msg: &[u8], positions: &mut [f32]) -> Result<PartHeader, DecodeError> {
    let (address, tags, mut r) = read_head(msg)?;
    if address != PART {
        return Err(DecodeError::UnknownAddress);
    }
    let Some(floats) = tags
        .strip_prefix(b"iiii")
        .filter(|f| f.iter().all(|&t| t == b'f'))
    else {
        return Err(DecodeError::WrongTypeTags);
    };
    let frame_number = r.i32()?;
    let mut ints = [0usize; 3];
    for (k, v) in ints.iter_mut().enumerate() {
        *v = usize::try_from(r.i32()?).map_err(|_| DecodeError::OutOfRange { index: k + 1 })?;
    }
    let [first, count, total] = ints;
    if floats.len() != 3 * count {
        return Err(DecodeError::WrongCount {
            expected: 3 * count,
            got: floats.len(),
        });
    }
    if first + count > total {
        return Err(DecodeError::OutOfRange { index: 2 });
    }
    if 3 * total > positions.len() {
        return Err(DecodeError::TooManyMarkers {
            markers: total,
            max: positions.len() / 3,
        });
    }
    let coords = r.take(12 * count)?;
    if r.remaining() != 0 {
        return Err(DecodeError::TrailingBytes {
            offset: r.pos(),
            extra: r.remaining(),
        });
    }
    let dst = &mut positions[3 * first..3 * (first + count)];
    for (i, (c, d)) in coords.chunks_exact(4).zip(dst.iter_mut()).enumerate() {
        *d = f32::from_be_bytes([c[0], c[1], c[2], c[3]]);
        if d.is_infinite() {
            return Err(DecodeError::NonFinite {
                marker: first + i / 3,
            });
        }
    }
    Ok(PartHeader {
        frame_number,
        first_marker: first,
        marker_count: count,
        total_markers: total,
    })
}

/// Decodes `/emoshift/components ,f...` into `u` without allocating; returns how many values.
///
/// # Errors
/// [`DecodeError::WrongTypeTags`], [`DecodeError::TooManyMarkers`] (more values than `u`
/// holds), truncation and trailing bytes.
pub fn decode_components_into(msg: &[u8], u: &mut [f32]) -> Result<usize, DecodeError> {
    let (address, tags, mut r) = read_head(msg)?;
    if address != COMPONENTS {
        return Err(DecodeError::UnknownAddress);
    }
    if !tags.iter().all(|&t| t == b'f') {
        return Err(DecodeError::WrongTypeTags);
    }
    let n = tags.len();
    if n > u.len() {
        return Err(DecodeError::TooManyMarkers {
            markers: n,
            max: u.len(),
        });
    }
    for v in &mut u[..n] {
        *v = r.f32()?;
    }
    if r.remaining() != 0 {
        return Err(DecodeError::TrailingBytes {
            offset: r.pos(),
            extra: r.remaining(),
        });
    }
    Ok(n)
}

/// The edit state of a compact bundle, `/emoshift/state ,sf`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State<'a> {
    /// Target emotion (or a blend, `sad:0.50,angry:0.50`); empty before one is set.
    pub target: &'a str,
    /// Amount now (glides included).
    pub amount: f32,
}

/// Decodes `/emoshift/state ,sf`, borrowing the target from `msg`.
///
/// # Errors
/// [`DecodeError::UnknownAddress`], [`DecodeError::WrongTypeTags`], a target that is not
/// UTF-8, truncation and trailing bytes.
pub fn decode_state(msg: &[u8]) -> Result<State<'_>, DecodeError> {
    let (target, amount) = string_float(msg, STATE)?;
    Ok(State { target, amount })
}

/// Decodes `/VMC/Ext/Blend/Val ,sf`: a blend name and its value.
///
/// # Errors
/// As [`decode_state`].
pub fn decode_blend_val(msg: &[u8]) -> Result<(&str, f32), DecodeError> {
    string_float(msg, VMC_BLEND_VAL)
}

fn string_float<'a>(msg: &'a [u8], expected: &str) -> Result<(&'a str, f32), DecodeError> {
    let (address, tags, mut r) = read_head(msg)?;
    if address != expected {
        return Err(DecodeError::UnknownAddress);
    }
    if tags != b"sf" {
        return Err(DecodeError::WrongTypeTags);
    }
    let at = r.pos();
    let text =
        std::str::from_utf8(r.str_bytes()?).map_err(|_| DecodeError::BadString { offset: at })?;
    let value = r.f32()?;
    if r.remaining() != 0 {
        return Err(DecodeError::TrailingBytes {
            offset: r.pos(),
            extra: r.remaining(),
        });
    }
    Ok((text, value))
}

/// Decodes `/emoshift/stream ,is`: the stream id and name.
///
/// # Errors
/// [`DecodeError`] if it is not that message.
pub fn decode_stream(msg: &[u8]) -> Result<(i32, &str), DecodeError> {
    let (address, tags, mut r) = read_head(msg)?;
    if address != crate::address::STREAM {
        return Err(DecodeError::UnknownAddress);
    }
    if tags != b"is" {
        return Err(DecodeError::WrongTypeTags);
    }
    let id = r.i32()?;
    let at = r.pos();
    let name =
        std::str::from_utf8(r.str_bytes()?).map_err(|_| DecodeError::BadString { offset: at })?;
    if r.remaining() != 0 {
        return Err(DecodeError::TrailingBytes {
            offset: r.pos(),
            extra: r.remaining(),
        });
    }
    Ok((id, name))
}
