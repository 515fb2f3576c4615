//! Marker frames: the allocation-free borrowed decoder and the encoder of `/mocap/frame`.

use crate::error::DecodeError;

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

mod decode;
mod encode;

pub use decode::decode_frame_into;
pub(crate) use encode::append_frame;
pub use encode::{encode_frame_flat_into, encode_frame_into, frame_message_len};

/// Whether every value is finite (positions on the wire and in the daemon's frame path).
/// No early exit, and integer arithmetic on the exponent bits,
/// so the loop vectorises on baseline SSE2; `iter().all(is_finite)` stops at
/// the first bad value and runs one scalar compare and branch per float (~0.1 µs a 109-marker
/// frame, measured, where this takes a fifth of that).
pub fn all_finite(values: &[f32]) -> bool {
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

#[cfg(test)]
mod tests;
