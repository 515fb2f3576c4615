//! `/mocap/timecode ,iiiii`: encoding, the source's frame bundle, decoding (see the table in
//! the parent module).

use super::{CaptureClock, FrameTime, Smpte, TimecodeRate};
use crate::address::TIMECODE;
use crate::error::{DecodeError, EncodeError};
use crate::frame::{append_frame, FrameBuf};
use crate::scan::read_head;
use crate::wire;

/// Bit 0 of the flags: a timecode is present.
const HAS_TIMECODE: i32 = 1;
/// Bit 1: drop-frame counting.
const DROP_FRAME: i32 = 2;
/// Bit 2: the capture time is µs since the Unix epoch on a synchronised clock.
const UTC_CLOCK: i32 = 4;

/// Appends `/mocap/timecode ,iiiii` (a whole message, no bundle element header) to `out`.
fn append_timecode(time: &FrameTime, out: &mut Vec<u8>) {
    wire::put_str_unchecked(out, TIMECODE);
    wire::put_str_unchecked(out, ",iiiii");
    let mut flags = 0;
    let (packed, sub, num, den) = match time.timecode {
        Some(t) => {
            flags |= HAS_TIMECODE;
            let (num, den) = t.rate.map_or((0, 1), |r| (r.numerator(), r.denominator()));
            if t.rate.is_some_and(|r| r.drop_frame()) {
                flags |= DROP_FRAME;
            }
            (t.packed(), t.subframe, num, den)
        }
        None => (0, 0, 0, 1),
    };
    if time.clock == CaptureClock::Utc {
        flags |= UTC_CLOCK;
    }
    for v in [packed, sub, num, den] {
        wire::put_u32(out, v);
    }
    wire::put_i32(out, flags);
}

/// Encodes `/mocap/timecode` alone into `out` (cleared first). Returns its length.
pub fn encode_timecode_into(time: &FrameTime, out: &mut Vec<u8>) -> usize {
    out.clear();
    append_timecode(time, out);
    out.len()
}

/// Appends `/mocap/timecode` as one more element of the bundle in `out` (an output bundle
/// that [`encode_compact_into`](crate::encode_compact_into) or
/// [`encode_components_into`](crate::encode_components_into) wrote).
pub fn append_timecode_element(time: &FrameTime, out: &mut Vec<u8>) {
    let at = wire::begin_element(out);
    append_timecode(time, out);
    wire::end_element(out, at);
}

/// Encodes a source's frame with its time: one bundle of `/mocap/timecode` and
/// `/mocap/frame ,ihbb` (or the bare frame when `time` has nothing to say), into `out`
/// (cleared first). Returns the encoded length.
///
/// # Errors
/// [`EncodeError::NonFinite`] if a present marker holds NaN or Inf.
pub fn encode_frame_timed_into(
    frame: &FrameBuf,
    time: &FrameTime,
    out: &mut Vec<u8>,
) -> Result<usize, EncodeError> {
    if !time.is_some() {
        return crate::encode_frame_into(frame, out);
    }
    out.clear();
    wire::put_bundle_header(out);
    append_timecode_element(time, out);
    let at = wire::begin_element(out);
    if let Err(e) = append_frame(frame, out) {
        out.clear();
        return Err(e);
    }
    wire::end_element(out, at);
    Ok(out.len())
}

/// Decodes a `/mocap/timecode` message, without allocating.
///
/// # Errors
/// [`DecodeError::UnknownAddress`], [`DecodeError::WrongTypeTags`] unless `,iiiii`,
/// [`DecodeError::OutOfRange`] naming the argument (a timecode out of range or a frame
/// number drop-frame skips, a zero denominator, drop-frame at a rate without it, unknown flag
/// bits), truncation and trailing bytes.
pub fn decode_timecode(msg: &[u8]) -> Result<FrameTime, DecodeError> {
    let (address, tags, mut r) = read_head(msg)?;
    if address != TIMECODE {
        return Err(DecodeError::UnknownAddress);
    }
    if tags != b"iiiii" {
        return Err(DecodeError::WrongTypeTags);
    }
    let (packed, sub, num, den, flags) = (r.u32()?, r.u32()?, r.u32()?, r.u32()?, r.i32()?);
    if r.remaining() != 0 {
        return Err(DecodeError::TrailingBytes {
            offset: r.pos(),
            extra: r.remaining(),
        });
    }
    if flags & !(HAS_TIMECODE | DROP_FRAME | UTC_CLOCK) != 0 {
        return Err(DecodeError::OutOfRange { index: 4 });
    }
    if sub > i32::MAX as u32 {
        return Err(DecodeError::OutOfRange { index: 1 });
    }
    let rate = match (num, den) {
        (0, _) if flags & DROP_FRAME == 0 => None,
        (_, 0) => return Err(DecodeError::OutOfRange { index: 3 }),
        (n, d) => Some(
            TimecodeRate::new(n, d, flags & DROP_FRAME != 0)
                .map_err(|_| DecodeError::OutOfRange { index: 2 })?,
        ),
    };
    let timecode = if flags & HAS_TIMECODE != 0 {
        let t = Smpte::from_packed(packed, sub, rate);
        if !t.is_valid() {
            return Err(DecodeError::OutOfRange { index: 0 });
        }
        Some(t)
    } else {
        None
    };
    let clock = if flags & UTC_CLOCK != 0 {
        CaptureClock::Utc
    } else {
        CaptureClock::Source
    };
    Ok(FrameTime {
        timecode,
        irig: None,
        clock,
    })
}
