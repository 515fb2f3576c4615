//! Data packets: timestamp (`i64`, µs), frame number (`u32`), component count, then each
//! component as size (header included), type, content. emoshift writes and reads the `3D`,
//! `3DRes`, `3DNoLabels` and `Timecode` components; a reader skips the others by their size.
//!
//! - `3D` / `3DRes`: marker count (`u32`), 2D drop rate and out-of-sync rate (`u16` each),
//!   then x y z (`f32`, mm; NaN for a marker not seen this frame, as QTM sends it), and with
//!   `3DRes` a residual after each (emoshift writes 0, and -1 for a missing marker).
//! - `3DNoLabels`: the same header, then x y z and an id (`u32`) per marker seen; emoshift's
//!   id is the label's 1-based index, and missing markers are left out.
//! - `Timecode`: a count, then per timecode type (`u32`: 0 SMPTE, 1 IRIG, 2 camera time),
//!   high and low words (`u32`). SMPTE in the low word: hours bits 0-4, minutes 5-10, seconds
//!   11-16, frames 17-21, subframes 22-30. IRIG: years 0-6 and days 7-15 of the high word,
//!   hours, minutes, seconds as SMPTE and tenths 17-20 of the low word.

use super::command::Components;
use super::error::QtmError;
use super::packet::{finish_packet, start_packet, PacketType, HEADER_BYTES};

/// Component type numbers.
pub const COMPONENT_3D: u32 = 1;
/// `3DNoLabels`.
pub const COMPONENT_3D_NO_LABELS: u32 = 2;
/// `3DRes`.
pub const COMPONENT_3D_RES: u32 = 9;
/// `Timecode`.
pub const COMPONENT_TIMECODE: u32 = 17;

/// A frame's timecode as QTM sends it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Timecode {
    /// SMPTE.
    Smpte {
        /// Hours.
        hours: u8,
        /// Minutes.
        minutes: u8,
        /// Seconds.
        seconds: u8,
        /// Frames.
        frames: u8,
        /// Subframes.
        subframes: u16,
    },
    /// IRIG.
    Irig {
        /// Years (two digits).
        years: u8,
        /// Day of the year.
        days: u16,
        /// Hours.
        hours: u8,
        /// Minutes.
        minutes: u8,
        /// Seconds.
        seconds: u8,
        /// Tenths of a second.
        tenths: u8,
    },
    /// The cameras' clock (ticks).
    CameraTime(u64),
}

impl Timecode {
    /// The type, high and low words.
    pub fn to_words(self) -> (u32, u32, u32) {
        match self {
            Timecode::Smpte {
                hours,
                minutes,
                seconds,
                frames,
                subframes,
            } => {
                let lo = u32::from(hours & 0x1f)
                    | u32::from(minutes & 0x3f) << 5
                    | u32::from(seconds & 0x3f) << 11
                    | u32::from(frames & 0x1f) << 17
                    | u32::from(subframes & 0x1ff) << 22;
                (0, 0, lo)
            }
            Timecode::Irig {
                years,
                days,
                hours,
                minutes,
                seconds,
                tenths,
            } => {
                let hi = u32::from(years & 0x7f) | u32::from(days & 0x1ff) << 7;
                let lo = u32::from(hours & 0x1f)
                    | u32::from(minutes & 0x3f) << 5
                    | u32::from(seconds & 0x3f) << 11
                    | u32::from(tenths & 0x0f) << 17;
                (1, hi, lo)
            }
            Timecode::CameraTime(t) => (2, (t >> 32) as u32, t as u32),
        }
    }

    /// From the type, high and low words; `None` for an unknown type.
    pub fn from_words(kind: u32, hi: u32, lo: u32) -> Option<Timecode> {
        let bits = |shift: u32, mask: u32| ((lo >> shift) & mask) as u8;
        Some(match kind {
            0 => Timecode::Smpte {
                hours: bits(0, 0x1f),
                minutes: bits(5, 0x3f),
                seconds: bits(11, 0x3f),
                frames: bits(17, 0x1f),
                subframes: ((lo >> 22) & 0x1ff) as u16,
            },
            1 => Timecode::Irig {
                years: (hi & 0x7f) as u8,
                days: ((hi >> 7) & 0x1ff) as u16,
                hours: bits(0, 0x1f),
                minutes: bits(5, 0x3f),
                seconds: bits(11, 0x3f),
                tenths: bits(17, 0x0f),
            },
            2 => Timecode::CameraTime(u64::from(hi) << 32 | u64::from(lo)),
            _ => return None,
        })
    }
}

/// One frame to encode: positions x y z per label (mm, NaN where missing).
#[derive(Debug, Clone, Copy)]
pub struct DataFrame<'a> {
    /// Microseconds, the source's capture clock.
    pub timestamp_us: i64,
    /// The frame number.
    pub frame_number: u32,
    /// x y z per label, NaN for a missing marker.
    pub positions: &'a [f32],
    /// The frame's timecode.
    pub timecode: Option<Timecode>,
}

/// Encodes a data packet with `components` into `out` (cleared first). A `Timecode` component
/// is written only when the frame has a timecode.
pub fn encode_data_into(frame: &DataFrame<'_>, components: Components, out: &mut Vec<u8>) {
    start_packet(PacketType::Data, out);
    out.extend_from_slice(&frame.timestamp_us.to_le_bytes());
    out.extend_from_slice(&frame.frame_number.to_le_bytes());
    let count_at = out.len();
    out.extend_from_slice(&0u32.to_le_bytes());
    let mut count = 0u32;
    let markers = frame.positions.chunks_exact(3);
    if components.d3 {
        let at = component_start(COMPONENT_3D, markers.len(), out);
        for xyz in markers.clone() {
            put_f32s(xyz, out);
        }
        component_end(at, out);
        count += 1;
    }
    if components.d3_res {
        let at = component_start(COMPONENT_3D_RES, markers.len(), out);
        for xyz in markers.clone() {
            put_f32s(xyz, out);
            let residual: f32 = if xyz.iter().any(|v| v.is_nan()) {
                -1.0
            } else {
                0.0
            };
            out.extend_from_slice(&residual.to_le_bytes());
        }
        component_end(at, out);
        count += 1;
    }
    if components.d3_no_labels {
        let seen = markers.clone().filter(|m| !m.iter().any(|v| v.is_nan()));
        let at = component_start(COMPONENT_3D_NO_LABELS, seen.count(), out);
        for (i, xyz) in markers.clone().enumerate() {
            if !xyz.iter().any(|v| v.is_nan()) {
                put_f32s(xyz, out);
                out.extend_from_slice(&(i as u32 + 1).to_le_bytes());
            }
        }
        component_end(at, out);
        count += 1;
    }
    if let (true, Some(tc)) = (components.timecode, frame.timecode) {
        let at = out.len();
        out.extend_from_slice(&[0; 4]);
        out.extend_from_slice(&COMPONENT_TIMECODE.to_le_bytes());
        out.extend_from_slice(&1u32.to_le_bytes());
        let (kind, hi, lo) = tc.to_words();
        for w in [kind, hi, lo] {
            out.extend_from_slice(&w.to_le_bytes());
        }
        component_end(at, out);
        count += 1;
    }
    out[count_at..count_at + 4].copy_from_slice(&count.to_le_bytes());
    finish_packet(out);
}

fn component_start(kind: u32, markers: usize, out: &mut Vec<u8>) -> usize {
    let at = out.len();
    out.extend_from_slice(&[0; 4]);
    out.extend_from_slice(&kind.to_le_bytes());
    out.extend_from_slice(&u32::try_from(markers).unwrap_or(u32::MAX).to_le_bytes());
    out.extend_from_slice(&[0; 4]); // 2D drop rate, 2D out-of-sync rate: none
    at
}

fn component_end(at: usize, out: &mut [u8]) {
    let size = u32::try_from(out.len() - at).unwrap_or(u32::MAX);
    out[at..at + 4].copy_from_slice(&size.to_le_bytes());
}

fn put_f32s(values: &[f32], out: &mut Vec<u8>) {
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

/// A decoded frame, in caller-owned buffers sized once ([`FrameIn::with_max_markers`]).
#[derive(Debug, Clone)]
pub struct FrameIn {
    /// Microseconds.
    pub timestamp_us: i64,
    /// The frame number.
    pub frame_number: u32,
    /// Whether a labelled 3D component (`3D` or `3DRes`) was in the packet.
    pub has_3d: bool,
    /// x y z per labelled marker (NaN where missing); `3 * marker_count` valid values.
    positions: Vec<f32>,
    marker_count: usize,
    /// The timecode, when the packet had one.
    pub timecode: Option<Timecode>,
}

impl FrameIn {
    /// Room for `max_markers` labelled markers.
    pub fn with_max_markers(max_markers: usize) -> FrameIn {
        FrameIn {
            timestamp_us: 0,
            frame_number: 0,
            has_3d: false,
            positions: vec![0.0; max_markers * 3],
            marker_count: 0,
            timecode: None,
        }
    }

    /// The labelled markers' x y z.
    pub fn positions(&self) -> &[f32] {
        &self.positions[..self.marker_count * 3]
    }

    /// Labelled markers in the frame.
    pub fn marker_count(&self) -> usize {
        self.marker_count
    }
}

/// Decodes a data packet's payload (after the 8-byte header) into `frame`; unknown
/// components are skipped by their size. No allocation.
///
/// # Errors
/// Truncation, a component size that disagrees with its content, more markers than `frame`
/// holds.
pub fn decode_data_into(payload: &[u8], frame: &mut FrameIn) -> Result<(), QtmError> {
    let r = Reader { bytes: payload };
    frame.timestamp_us = i64::from_le_bytes(r.array(0)?);
    frame.frame_number = r.u32(8)?;
    let count = r.u32(12)?;
    frame.has_3d = false;
    frame.marker_count = 0;
    frame.timecode = None;
    let mut at = 16;
    for _ in 0..count {
        let size = r.u32(at)?;
        let kind = r.u32(at + 4)?;
        let end = at
            .checked_add(size as usize)
            .filter(|&e| size as usize >= 8 && e <= payload.len())
            .ok_or(QtmError::ComponentSize {
                offset: at + HEADER_BYTES,
                declared: size,
                needed: payload.len().saturating_sub(at),
            })?;
        let body = Reader {
            bytes: &payload[at + 8..end],
        };
        match kind {
            COMPONENT_3D | COMPONENT_3D_RES => {
                read_3d(&body, kind == COMPONENT_3D_RES, frame, at + HEADER_BYTES)?;
            }
            COMPONENT_TIMECODE if body.u32(0)? > 0 => {
                frame.timecode = Timecode::from_words(body.u32(4)?, body.u32(8)?, body.u32(12)?);
            }
            _ => {}
        }
        at = end;
    }
    Ok(())
}

fn read_3d(
    body: &Reader<'_>,
    res: bool,
    frame: &mut FrameIn,
    offset: usize,
) -> Result<(), QtmError> {
    let count = body.u32(0)?;
    let stride = if res { 16 } else { 12 };
    let needed = 8 + count as usize * stride;
    if needed != body.bytes.len() {
        return Err(QtmError::ComponentSize {
            offset,
            declared: u32::try_from(body.bytes.len() + 8).unwrap_or(u32::MAX),
            needed: needed + 8,
        });
    }
    if count as usize * 3 > frame.positions.len() {
        return Err(QtmError::TooManyMarkers {
            count,
            max: frame.positions.len() / 3,
        });
    }
    for i in 0..count as usize {
        for k in 0..3 {
            frame.positions[3 * i + k] = f32::from_le_bytes(body.array(8 + i * stride + 4 * k)?);
        }
    }
    frame.marker_count = count as usize;
    frame.has_3d = true;
    Ok(())
}

struct Reader<'a> {
    bytes: &'a [u8],
}

impl Reader<'_> {
    fn array<const N: usize>(&self, at: usize) -> Result<[u8; N], QtmError> {
        self.bytes
            .get(at..at + N)
            .and_then(|b| b.try_into().ok())
            .ok_or(QtmError::Truncated {
                offset: at + HEADER_BYTES,
            })
    }

    fn u32(&self, at: usize) -> Result<u32, QtmError> {
        self.array(at).map(u32::from_le_bytes)
    }
}
