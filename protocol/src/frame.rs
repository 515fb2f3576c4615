//! Marker frames: the allocation-free borrowed decoder and the encoder of `/mocap/frame`.

use crate::address::FRAME;
use crate::error::{DecodeError, EncodeError};
use crate::scan::read_head;
use crate::wire::{self, Reader};

/// Upper bound on the markers one datagram of at most 65,507 bytes can carry (blob form:
/// 12 bytes a marker plus a bit of mask); the default capacity of [`FrameBuf`].
pub const MAX_FRAME_MARKERS: usize = 5_400;

/// Which of the two accepted encodings a frame arrived in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FrameForm {
    /// `,ihbb`: frame, time, missing-marker bitmask blob, positions blob.
    Blob,
    /// `,ih` followed by 3n floats, NaN meaning missing.
    Flat,
}

/// The scalar part of a decoded frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameHeader {
    /// Sender's frame number.
    pub frame_number: i32,
    /// Capture time in microseconds on the sender's clock.
    pub capture_time_us: i64,
    /// Markers in the frame (positions hold 3 times as many floats).
    pub marker_count: usize,
    /// How many of them are missing.
    pub missing_count: usize,
    /// The encoding the frame arrived in.
    pub form: FrameForm,
}

/// Caller-owned frame storage, allocated once; decoding and editing never reallocate it.
///
/// Positions are x y z per marker in millimetres, in label order. A missing marker's three
/// coordinates read as NaN, whichever form it arrived in, and its bit is set in the mask.
#[derive(Debug, Clone)]
pub struct FrameBuf {
    positions: Vec<f32>,
    missing: Vec<u8>,
    max_markers: usize,
    header: FrameHeader,
}

impl Default for FrameBuf {
    fn default() -> Self {
        Self::new()
    }
}

impl FrameBuf {
    /// A buffer for any frame a datagram can carry ([`MAX_FRAME_MARKERS`], about 64 KiB).
    pub fn new() -> Self {
        Self::with_max_markers(MAX_FRAME_MARKERS)
    }

    /// A buffer for at most `max_markers` markers; larger frames are rejected with
    /// [`DecodeError::TooManyMarkers`] instead of growing the buffer.
    pub fn with_max_markers(max_markers: usize) -> Self {
        FrameBuf {
            positions: Vec::with_capacity(max_markers * 3),
            missing: Vec::with_capacity(max_markers.div_ceil(8)),
            max_markers,
            header: FrameHeader {
                frame_number: 0,
                capture_time_us: 0,
                marker_count: 0,
                missing_count: 0,
                form: FrameForm::Blob,
            },
        }
    }

    /// The capacity in markers.
    pub fn max_markers(&self) -> usize {
        self.max_markers
    }

    /// Header of the frame held.
    pub fn header(&self) -> FrameHeader {
        self.header
    }

    /// Sets frame number and capture time, e.g. before encoding an edited frame.
    pub fn set_header(&mut self, frame_number: i32, capture_time_us: i64) {
        self.header.frame_number = frame_number;
        self.header.capture_time_us = capture_time_us;
    }

    /// Markers held.
    pub fn marker_count(&self) -> usize {
        self.header.marker_count
    }

    /// x y z per marker, NaN for missing markers.
    pub fn positions(&self) -> &[f32] {
        &self.positions
    }

    /// Mutable positions, for editing in place. Writing a non-finite value into a present
    /// marker makes [`encode_frame_into`] fail; use [`FrameBuf::set_missing`] instead.
    pub fn positions_mut(&mut self) -> &mut [f32] {
        &mut self.positions
    }

    /// The missing-marker bitmask as on the wire: marker i is bit i mod 8 of byte i div 8.
    pub fn missing_mask(&self) -> &[u8] {
        &self.missing
    }

    /// Whether marker `i` is missing (`false` past the end).
    pub fn is_missing(&self, i: usize) -> bool {
        self.missing
            .get(i / 8)
            .is_some_and(|b| b >> (i % 8) & 1 == 1)
    }

    /// Marks marker `i` missing (its coordinates become NaN) or present (coordinates kept;
    /// write finite ones before encoding). Out-of-range indices are ignored.
    pub fn set_missing(&mut self, i: usize, missing: bool) {
        if i >= self.marker_count() {
            return;
        }
        let bit = 1u8 << (i % 8);
        let was = self.is_missing(i);
        if missing {
            self.missing[i / 8] |= bit;
            self.positions[3 * i..3 * i + 3].fill(f32::NAN);
        } else {
            self.missing[i / 8] &= !bit;
        }
        match (was, missing) {
            (false, true) => self.header.missing_count += 1,
            (true, false) => self.header.missing_count -= 1,
            _ => {}
        }
    }

    /// Fills the buffer from x y z triples, an all-NaN triple meaning missing: how a source
    /// (replay, tests) builds a frame to encode.
    ///
    /// # Errors
    /// [`DecodeError::WrongCount`] if `positions.len()` is not a multiple of 3,
    /// [`DecodeError::TooManyMarkers`], [`DecodeError::PartlyMissing`], [`DecodeError::NonFinite`].
    pub fn set_frame(
        &mut self,
        frame_number: i32,
        capture_time_us: i64,
        positions: &[f32],
    ) -> Result<(), DecodeError> {
        if positions.len() % 3 != 0 {
            return Err(DecodeError::WrongCount {
                expected: positions.len() / 3 * 3,
                got: positions.len(),
            });
        }
        if all_finite(positions) {
            // the common case (an edited or synthetic frame, nothing missing): one copy
            let n = positions.len() / 3;
            self.reset_empty(n, FrameForm::Flat)?;
            self.set_header(frame_number, capture_time_us);
            self.positions.extend_from_slice(positions);
            self.missing.resize(n.div_ceil(8), 0);
            return Ok(());
        }
        self.reset(positions.len() / 3, FrameForm::Flat)?;
        self.set_header(frame_number, capture_time_us);
        for (m, xyz) in positions.chunks_exact(3).enumerate() {
            self.put_flat_marker(m, [xyz[0], xyz[1], xyz[2]])?;
        }
        Ok(())
    }

    /// Empties the buffer for `n` markers, all present at the origin, without reallocating.
    fn reset(&mut self, n: usize, form: FrameForm) -> Result<(), DecodeError> {
        self.reset_empty(n, form)?;
        self.positions.resize(n * 3, 0.0);
        self.missing.resize(n.div_ceil(8), 0);
        Ok(())
    }

    /// Checks capacity and sets the header for `n` markers, leaving positions and mask empty
    /// for the caller to fill with exactly `3 n` and `n.div_ceil(8)` values.
    fn reset_empty(&mut self, n: usize, form: FrameForm) -> Result<(), DecodeError> {
        if n > self.max_markers {
            return Err(DecodeError::TooManyMarkers {
                markers: n,
                max: self.max_markers,
            });
        }
        self.positions.clear();
        self.missing.clear();
        self.header.marker_count = n;
        self.header.missing_count = 0;
        self.header.form = form;
        Ok(())
    }

    /// Stores one marker of the flat form: finite, or all NaN for missing.
    fn put_flat_marker(&mut self, m: usize, xyz: [f32; 3]) -> Result<(), DecodeError> {
        let nans = xyz.iter().filter(|v| v.is_nan()).count();
        match nans {
            0 if xyz.iter().all(|v| v.is_finite()) => {
                self.positions[3 * m..3 * m + 3].copy_from_slice(&xyz);
                Ok(())
            }
            0 => Err(DecodeError::NonFinite { marker: m }),
            3 => {
                self.set_missing(m, true);
                Ok(())
            }
            _ => Err(DecodeError::PartlyMissing { marker: m }),
        }
    }
}

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

/// Whether every value is finite. No early exit, and integer arithmetic on the exponent bits,
/// so the loop vectorises on baseline SSE2; `iter().all(is_finite)` stops at
/// the first bad value and runs one scalar compare and branch per float (~0.1 µs a 109-marker
/// frame, measured, where this takes a fifth of that).
pub(crate) fn all_finite(values: &[f32]) -> bool {
    const EXP: u32 = 0x7f80_0000;
    let chunks = values.chunks_exact(8);
    let tail = chunks.remainder().iter().all(|v| v.is_finite());
    // An all-ones exponent (Inf, NaN) plus its lowest bit carries into bit 31; any other
    // exponent stays below it. Mask, add, or: three plain vector ops per four floats.
    let mut bits = [0_u32; 8];
    for c in chunks {
        for i in 0..8 {
            bits[i] |= (c[i].to_bits() & EXP) + 0x0080_0000;
        }
    }
    tail && bits.iter().fold(0, |a, b| a | b) >> 31 == 0
}

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
    wire::put_str_unchecked(out, FRAME);
    out.extend_from_slice(b",ih");
    out.resize(out.len() + frame.positions.len(), b'f');
    out.push(0);
    wire::pad_to4(out, 0);
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

#[cfg(test)]
mod tests {
    use super::all_finite;

    #[test]
    fn all_finite_finds_any_bad_value_in_lanes_and_tail() {
        for len in 0..21 {
            let mut v: Vec<f32> = (0..len).map(|i| i as f32 - 7.5).collect();
            v.iter_mut().take(1).for_each(|x| *x = f32::MAX);
            v.iter_mut()
                .skip(1)
                .take(1)
                .for_each(|x| *x = -f32::MIN_POSITIVE / 2.0);
            assert!(all_finite(&v), "len {len}");
            for at in 0..len {
                for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                    let mut w = v.clone();
                    w[at] = bad;
                    assert!(!all_finite(&w), "len {len}, {bad} at {at}");
                }
            }
        }
    }
}
