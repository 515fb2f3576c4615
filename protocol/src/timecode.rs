//! The source's time of a frame: SMPTE timecode (`hh:mm:ss:ff`, subframe, rate, drop-frame)
//! and what the frame's capture time means ([`FrameTime`]); `/mocap/timecode`, its OSC form.
//!
//! # `/mocap/timecode ,iiiii`
//!
//! Sent in the same bundle as the `/mocap/frame` it belongs to (a source's datagram, and the
//! daemon's compact output). Today's `/mocap/frame` stays valid on its own: a frame without a
//! timecode message simply has none.
//!
//! | argument | meaning |
//! |---|---|
//! | `i` | SMPTE timecode packed `hh << 24 \| mm << 16 \| ss << 8 \| ff` (NatNet's packing) |
//! | `i` | subframe (0-based; e.g. 0..3 for 120 Hz capture on 30 fps timecode) |
//! | `i` | timecode rate numerator, frames per second as a fraction (`30000` for 29.97); 0 = unknown |
//! | `i` | rate denominator (`1001` for 29.97); 1 when the numerator is 0 |
//! | `i` | flags: bit 0 a timecode is present, bit 1 drop-frame counting, bit 2 the frame's capture time is µs since the Unix epoch on a synchronised clock (PTP/NTP); other bits 0 |
//!
//! 44 bytes. Drop-frame is only valid at 30000/1001 and 60000/1001, where the first 2 (4)
//! frame numbers of every minute not divisible by ten do not exist.

use std::fmt;

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
/// Bytes of an encoded `/mocap/timecode`.
pub const TIMECODE_MESSAGE_LEN: usize = 16 + 8 + 20;

/// A timecode rate: frames per second as a fraction, and whether frames are counted
/// drop-frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TimecodeRate {
    numerator: u32,
    denominator: u32,
    drop_frame: bool,
}

/// Why a timecode rate or a timecode is refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TimecodeError {
    /// Not a rate this module can read.
    #[error(
        "{text:?} is not a timecode rate: give e.g. 24, 25, 29.97df, 30, 59.94df, 60 or 30000/1001"
    )]
    Rate {
        /// What was given.
        text: String,
    },
    /// Drop-frame at a rate that has none.
    #[error("drop-frame timecode exists only at 29.97 and 59.94 fps, not {fps:.3}")]
    DropFrame {
        /// The rate.
        fps: f64,
    },
    /// Not `hh:mm:ss:ff` (or `;ff` for drop-frame), optionally `.subframe`.
    #[error("{text:?} is not a timecode hh:mm:ss:ff[.sub]")]
    Timecode {
        /// What was given.
        text: String,
    },
}

impl TimecodeRate {
    /// 24 fps.
    pub const FPS_24: TimecodeRate = TimecodeRate::exact(24);
    /// 25 fps.
    pub const FPS_25: TimecodeRate = TimecodeRate::exact(25);
    /// 30 fps.
    pub const FPS_30: TimecodeRate = TimecodeRate::exact(30);
    /// 29.97 fps drop-frame (30000/1001 DF).
    pub const DF_29_97: TimecodeRate = TimecodeRate {
        numerator: 30_000,
        denominator: 1_001,
        drop_frame: true,
    };

    const fn exact(fps: u32) -> TimecodeRate {
        TimecodeRate {
            numerator: fps,
            denominator: 1,
            drop_frame: false,
        }
    }

    /// `numerator / denominator` frames per second, drop-frame or not.
    ///
    /// # Errors
    /// [`TimecodeError::Rate`] for a zero part or a rate over 1,000 fps;
    /// [`TimecodeError::DropFrame`] for drop-frame at a rate that has none.
    pub fn new(numerator: u32, denominator: u32, drop_frame: bool) -> Result<Self, TimecodeError> {
        let rate = TimecodeRate {
            numerator,
            denominator,
            drop_frame,
        };
        if numerator == 0 || denominator == 0 || rate.fps() > 1_000.0 {
            return Err(TimecodeError::Rate {
                text: format!("{numerator}/{denominator}"),
            });
        }
        if drop_frame && !(denominator == 1_001 && matches!(rate.nominal_fps(), 30 | 60)) {
            return Err(TimecodeError::DropFrame { fps: rate.fps() });
        }
        Ok(rate)
    }

    /// Reads `24`, `25`, `29.97`, `29.97df`, `30`, `59.94df`, `60`, `23.976`, `30000/1001`,
    /// `30000/1001df` (a `ndf` suffix is accepted and means non-drop). The NTSC rates
    /// written as decimals (23.976, 29.97, 47.952, 59.94, 119.88) are the exact x/1001 rates.
    ///
    /// # Errors
    /// As [`TimecodeRate::new`], or text that is no rate.
    pub fn parse(text: &str) -> Result<Self, TimecodeError> {
        let bad = || TimecodeError::Rate { text: text.into() };
        let t = text.trim().to_ascii_lowercase();
        let (body, df) = match t.strip_suffix("ndf") {
            Some(b) => (b, false),
            None => match t.strip_suffix("df") {
                Some(b) => (b, true),
                None => (t.as_str(), false),
            },
        };
        let body = body.trim_end_matches([' ', '-', '_']);
        if let Some((n, d)) = body.split_once('/') {
            let n = n.trim().parse().map_err(|_| bad())?;
            let d = d.trim().parse().map_err(|_| bad())?;
            return TimecodeRate::new(n, d, df);
        }
        let fps: f64 = body.parse().map_err(|_| bad())?;
        if !(fps.is_finite() && fps > 0.0) {
            return Err(bad());
        }
        let whole = fps.round();
        if (fps - whole).abs() < 1e-9 {
            return TimecodeRate::new(whole as u32, 1, df);
        }
        let ntsc = (fps * 1.001).round();
        if (fps - ntsc / 1.001).abs() < 0.001 {
            return TimecodeRate::new(ntsc as u32 * 1_000, 1_001, df);
        }
        Err(bad())
    }

    /// Numerator of frames per second.
    pub fn numerator(&self) -> u32 {
        self.numerator
    }

    /// Denominator of frames per second.
    pub fn denominator(&self) -> u32 {
        self.denominator
    }

    /// Whether frames are counted drop-frame.
    pub fn drop_frame(&self) -> bool {
        self.drop_frame
    }

    /// Frames per second.
    pub fn fps(&self) -> f64 {
        f64::from(self.numerator) / f64::from(self.denominator.max(1))
    }

    /// Frame numbers per timecode second: the rate rounded (30 for 29.97).
    pub fn nominal_fps(&self) -> u32 {
        ((f64::from(self.numerator) / f64::from(self.denominator.max(1))).round() as u32).max(1)
    }

    /// Frame numbers skipped at the start of each minute not divisible by ten (0 without
    /// drop-frame; 2 at 29.97, 4 at 59.94).
    fn dropped_per_minute(&self) -> u32 {
        if self.drop_frame {
            self.nominal_fps() / 15
        } else {
            0
        }
    }
}

/// `30`, `29.97df`, `30000/1001` (non-drop 29.97): what [`TimecodeRate::parse`] reads back.
impl fmt::Display for TimecodeRate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.denominator {
            1 => write!(f, "{}", self.numerator)?,
            1_001 if self.numerator % 1_000 == 0 => {
                let text = format!("{:.3}", self.fps());
                f.write_str(text.trim_end_matches('0'))?;
            }
            d => write!(f, "{}/{d}", self.numerator)?,
        }
        if self.drop_frame {
            f.write_str("df")?;
        }
        Ok(())
    }
}

/// An SMPTE timecode: hours, minutes, seconds, frames, a subframe, and its rate if known.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Smpte {
    /// Hours, 0..24.
    pub hours: u8,
    /// Minutes, 0..60.
    pub minutes: u8,
    /// Seconds, 0..60.
    pub seconds: u8,
    /// Frames, 0..nominal fps.
    pub frames: u8,
    /// Subframe (0-based).
    pub subframe: u32,
    /// The timecode rate, when the source says (NatNet does not: `serve` takes it from the
    /// config).
    pub rate: Option<TimecodeRate>,
}

impl Smpte {
    /// Unpacks NatNet's `hh mm ss ff` packing (most significant byte first).
    pub fn from_packed(packed: u32, subframe: u32, rate: Option<TimecodeRate>) -> Smpte {
        let [hours, minutes, seconds, frames] = packed.to_be_bytes();
        Smpte {
            hours,
            minutes,
            seconds,
            frames,
            subframe,
            rate,
        }
    }

    /// Packs as NatNet does.
    pub fn packed(&self) -> u32 {
        u32::from_be_bytes([self.hours, self.minutes, self.seconds, self.frames])
    }

    /// Whether every field is in range, and for drop-frame whether the frame number exists.
    pub fn is_valid(&self) -> bool {
        let fps = self
            .rate
            .map_or(u32::from(u8::MAX) + 1, |r| r.nominal_fps());
        let in_range = self.hours < 24
            && self.minutes < 60
            && self.seconds < 60
            && u32::from(self.frames) < fps;
        let dropped = self.rate.map_or(0, |r| r.dropped_per_minute());
        let skipped =
            self.seconds == 0 && u32::from(self.frames) < dropped && self.minutes % 10 != 0;
        in_range && !skipped
    }

    /// Frames since 00:00:00:00 at the timecode's rate (drop-frame aware); `None` without a
    /// rate or for an invalid timecode.
    pub fn frame_count(&self) -> Option<u64> {
        let rate = self.rate?;
        if !self.is_valid() {
            return None;
        }
        let fps = u64::from(rate.nominal_fps());
        let minutes = u64::from(self.hours) * 60 + u64::from(self.minutes);
        let nominal = (minutes * 60 + u64::from(self.seconds)) * fps + u64::from(self.frames);
        let d = u64::from(rate.dropped_per_minute());
        Some(nominal - d * (minutes - minutes / 10))
    }

    /// The timecode `count` frames after 00:00:00:00 at `rate` (drop-frame aware), wrapping
    /// at 24 hours; subframe 0.
    pub fn from_frame_count(count: u64, rate: TimecodeRate) -> Smpte {
        let fps = u64::from(rate.nominal_fps());
        let d = u64::from(rate.dropped_per_minute());
        let per_day = fps * 86_400 - d * (24 * 60 - 24 * 6);
        let mut n = count % per_day;
        if d > 0 {
            let per_ten = fps * 600 - d * 9;
            let per_minute = fps * 60 - d;
            let (tens, rest) = (n / per_ten, n % per_ten);
            n += d * 9 * tens;
            if rest >= d {
                n += d * ((rest - d) / per_minute);
            }
        }
        let frames = n % fps;
        let secs = n / fps;
        Smpte {
            hours: (secs / 3_600) as u8,
            minutes: (secs / 60 % 60) as u8,
            seconds: (secs % 60) as u8,
            frames: frames as u8,
            subframe: 0,
            rate: Some(rate),
        }
    }

    /// Reads `hh:mm:ss:ff`, `hh:mm:ss;ff` (drop-frame) with an optional `.subframe`, at
    /// `rate` (whose drop-frame flag wins over the separator).
    ///
    /// # Errors
    /// [`TimecodeError::Timecode`] for anything else, or a timecode out of range.
    pub fn parse(text: &str, rate: Option<TimecodeRate>) -> Result<Smpte, TimecodeError> {
        let bad = || TimecodeError::Timecode { text: text.into() };
        let (main, sub) = match text.trim().split_once('.') {
            Some((m, s)) => (m, s.parse().map_err(|_| bad())?),
            None => (text.trim(), 0),
        };
        let parts: Vec<&str> = main.split([':', ';']).collect();
        let [h, m, s, f] = parts.as_slice() else {
            return Err(bad());
        };
        let num = |p: &str| p.parse::<u8>().map_err(|_| bad());
        let t = Smpte {
            hours: num(h)?,
            minutes: num(m)?,
            seconds: num(s)?,
            frames: num(f)?,
            subframe: sub,
            rate,
        };
        if t.is_valid() {
            Ok(t)
        } else {
            Err(bad())
        }
    }
}

/// `hh:mm:ss:ff.s`, with `;` before the frames for drop-frame (the SMPTE convention).
impl fmt::Display for Smpte {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sep = if self.rate.is_some_and(|r| r.drop_frame()) {
            ';'
        } else {
            ':'
        };
        write!(
            f,
            "{:02}:{:02}:{:02}{sep}{:02}.{}",
            self.hours, self.minutes, self.seconds, self.frames, self.subframe
        )
    }
}

/// Which clock a frame's capture time is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum CaptureClock {
    /// The source's own clock, of unknown epoch (NatNet: the server's high-resolution clock,
    /// whose offset the echo measures).
    #[default]
    Source,
    /// Microseconds since the Unix epoch on a clock synchronised with the receiver's (PTP,
    /// NTP): end-to-end latency can be measured against the system clock.
    Utc,
}

/// The source's time of one frame, beside its frame number and capture time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct FrameTime {
    /// SMPTE timecode, when the source stamps one.
    pub timecode: Option<Smpte>,
    /// What the capture time is measured on.
    pub clock: CaptureClock,
}

impl FrameTime {
    /// Whether there is anything to send (a timecode, or a clock other than the source's).
    pub fn is_some(&self) -> bool {
        self.timecode.is_some() || self.clock != CaptureClock::Source
    }
}

/// Appends `/mocap/timecode ,iiiii` (a whole message, no bundle element header) to `out`.
pub(crate) fn append_timecode(time: &FrameTime, out: &mut Vec<u8>) {
    wire::put_str_unchecked(out, TIMECODE);
    wire::put_str_unchecked(out, ",iiiii");
    let mut flags = 0;
    let (packed, sub, num, den) = match time.timecode {
        Some(t) => {
            flags |= HAS_TIMECODE;
            let (num, den) = t.rate.map_or((0, 1), |r| (r.numerator, r.denominator));
            if t.rate.is_some_and(|r| r.drop_frame) {
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
    Ok(FrameTime { timecode, clock })
}

#[cfg(test)]
#[path = "timecode_tests.rs"]
mod tests;
