//! The source's time of a frame: SMPTE timecode (`hh:mm:ss:ff`, subframe, rate, drop-frame),
//! IRIG time of day ([`Irig`], from QTM) and what the frame's capture time means
//! ([`FrameTime`]); `/mocap/timecode`, its OSC form (SMPTE only).
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
    /// IRIG time of day, when the source stamps one (QTM with an IRIG clock). Only QTM's
    /// output says it again; NatNet and `/mocap/timecode` carry SMPTE only, so a frame with
    /// IRIG alone goes out there without a timecode.
    pub irig: Option<Irig>,
    /// What the capture time is measured on.
    pub clock: CaptureClock,
}

impl FrameTime {
    /// Whether there is anything to send as `/mocap/timecode` (an SMPTE timecode, or a clock
    /// other than the source's).
    pub fn is_some(&self) -> bool {
        self.timecode.is_some() || self.clock != CaptureClock::Source
    }
}

mod irig;
mod message;

pub use irig::Irig;

pub use message::{
    append_timecode_element, decode_timecode, encode_frame_timed_into, encode_timecode_into,
};

#[cfg(test)]
mod tests;
