//! A frame or time range of a take: `convert --start/--end`, `edit --start/--end` and a
//! manifest take's `start`/`end` share this one syntax and this one reading (issue 37).

use std::fmt;
use std::ops::Range;
use std::str::FromStr;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// One end of a range: a frame number as the file numbers it (`240`), or seconds from the
/// take's first frame (`2.5s`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrameOrTime {
    /// A frame number, as the file numbers its frames.
    Frame(i64),
    /// Seconds from the first frame.
    Seconds(f64),
}

impl FromStr for FrameOrTime {
    type Err = String;

    fn from_str(text: &str) -> Result<FrameOrTime, String> {
        let bad = || format!("{text:?} is neither a frame number (240) nor a time (2.5s)");
        match text.trim().strip_suffix('s') {
            Some(secs) => secs
                .trim()
                .parse::<f64>()
                .ok()
                .filter(|s| s.is_finite() && *s >= 0.0)
                .map(FrameOrTime::Seconds)
                .ok_or_else(bad),
            None => text
                .trim()
                .parse()
                .map(FrameOrTime::Frame)
                .map_err(|_| bad()),
        }
    }
}

impl fmt::Display for FrameOrTime {
    /// As it is written: `240` or `2.5s`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FrameOrTime::Frame(n) => write!(f, "{n}"),
            FrameOrTime::Seconds(s) => write!(f, "{s}s"),
        }
    }
}

impl FrameOrTime {
    /// The 0-based frame index this names in a take whose first frame is numbered
    /// `first_frame`, at `rate_hz` (negative before the take, past its end after it).
    pub fn index(self, first_frame: i64, rate_hz: f64) -> i64 {
        match self {
            FrameOrTime::Frame(n) => n - first_frame,
            FrameOrTime::Seconds(s) => (s * rate_hz).round() as i64,
        }
    }
}

/// In TOML a frame is an integer (`start = 240`) and a time a string (`start = "2.5s"`); a
/// string frame number (`"240"`) reads too.
impl Serialize for FrameOrTime {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            FrameOrTime::Frame(n) => serializer.serialize_i64(*n),
            FrameOrTime::Seconds(_) => serializer.collect_str(self),
        }
    }
}

impl<'de> Deserialize<'de> for FrameOrTime {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<FrameOrTime, D::Error> {
        deserializer.deserialize_any(Visitor)
    }
}

struct Visitor;

impl serde::de::Visitor<'_> for Visitor {
    type Value = FrameOrTime;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a frame number (240) or a time in seconds as a string (\"2.5s\")")
    }

    fn visit_i64<E: serde::de::Error>(self, n: i64) -> Result<FrameOrTime, E> {
        Ok(FrameOrTime::Frame(n))
    }

    fn visit_u64<E: serde::de::Error>(self, n: u64) -> Result<FrameOrTime, E> {
        i64::try_from(n)
            .map(FrameOrTime::Frame)
            .map_err(|_| E::custom(format!("frame {n} is too large")))
    }

    fn visit_f64<E: serde::de::Error>(self, s: f64) -> Result<FrameOrTime, E> {
        Err(E::custom(format!(
            "{s} is not a frame number; write a time as a string ending in s (\"{s}s\") or a \
             whole frame number (240)"
        )))
    }

    fn visit_str<E: serde::de::Error>(self, text: &str) -> Result<FrameOrTime, E> {
        text.parse().map_err(E::custom)
    }
}

/// Why a range does not fit its take.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RangeError {
    /// The end comes before the start.
    #[error(
        "end = {end} is before start = {start}: start names the first frame kept and end the \
         last"
    )]
    EndBeforeStart {
        /// The start as written.
        start: FrameOrTime,
        /// The end as written.
        end: FrameOrTime,
    },
    /// An end of the range lies outside the take.
    #[error(
        "{which} = {at} is outside the take, which has frames {first_frame} to {last_frame} \
         ({last_s:.3} s at {rate_hz} Hz): write a {which} within those, or leave it out for \
         the take's own"
    )]
    OutsideTake {
        /// `start` or `end`.
        which: &'static str,
        /// The value as written.
        at: FrameOrTime,
        /// The take's first frame number.
        first_frame: i64,
        /// The take's last frame number.
        last_frame: i64,
        /// Time of its last frame, seconds from the first.
        last_s: f64,
        /// Its rate.
        rate_hz: f64,
    },
}

/// A take's `start`..=`end`, either left out for the take's own.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TakeRange {
    /// First frame kept.
    pub start: Option<FrameOrTime>,
    /// Last frame kept, inclusive.
    pub end: Option<FrameOrTime>,
}

impl TakeRange {
    /// The whole take.
    pub const WHOLE: TakeRange = TakeRange {
        start: None,
        end: None,
    };

    /// Whether neither end is given.
    pub fn is_whole(&self) -> bool {
        self.start.is_none() && self.end.is_none()
    }

    /// The end before the start when both are the same kind (both frames or both times),
    /// which no take can fix; a mixed pair is checked against its take by [`TakeRange::frames`].
    ///
    /// # Errors
    /// [`RangeError::EndBeforeStart`].
    pub fn check_order(&self) -> Result<(), RangeError> {
        let backwards = match (self.start, self.end) {
            (Some(FrameOrTime::Frame(s)), Some(FrameOrTime::Frame(e))) => e < s,
            (Some(FrameOrTime::Seconds(s)), Some(FrameOrTime::Seconds(e))) => e < s,
            _ => false,
        };
        match (backwards, self.start, self.end) {
            (true, Some(start), Some(end)) => Err(RangeError::EndBeforeStart { start, end }),
            _ => Ok(()),
        }
    }

    /// The frame indices kept of a take of `frames` frames whose first is numbered
    /// `first_frame`, at `rate_hz`. Unlike `convert`, which keeps what overlaps the take, a
    /// manifest's range must lie within its take: one that does not names another take or
    /// rate than the user thought.
    ///
    /// # Errors
    /// An end outside the take, or the end before the start.
    pub fn frames(
        &self,
        first_frame: i64,
        rate_hz: f64,
        frames: usize,
    ) -> Result<Range<usize>, RangeError> {
        let n = frames as i64;
        let outside = |which, at| RangeError::OutsideTake {
            which,
            at,
            first_frame,
            last_frame: first_frame + n - 1,
            last_s: frames.saturating_sub(1) as f64 / rate_hz,
            rate_hz,
        };
        let index = |which, at: Option<FrameOrTime>, whole: i64| match at {
            None => Ok(whole),
            Some(at) => {
                let i = at.index(first_frame, rate_hz);
                (0..n).contains(&i).then_some(i).ok_or(outside(which, at))
            }
        };
        let from = index("start", self.start, 0)?;
        let last = index("end", self.end, n - 1)?;
        if let (true, Some(start), Some(end)) = (last < from, self.start, self.end) {
            return Err(RangeError::EndBeforeStart { start, end });
        }
        Ok(from as usize..(last + 1).max(from) as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_and_times_name_the_same_range() {
        let by_frame = TakeRange {
            start: "101".parse().ok(),
            end: "300".parse().ok(),
        };
        let by_time = TakeRange {
            start: "1s".parse().ok(),
            end: "2.99s".parse().ok(),
        };
        assert_eq!(by_frame.frames(1, 100.0, 500), Ok(100..300));
        assert_eq!(by_time.frames(1, 100.0, 500), Ok(100..300));
        assert_eq!(TakeRange::WHOLE.frames(1, 100.0, 500), Ok(0..500));
    }

    #[test]
    fn a_range_outside_its_take_or_backwards_is_refused() {
        let range = |s: &str, e: &str| TakeRange {
            start: s.parse().ok(),
            end: e.parse().ok(),
        };
        let err = range("1", "600").frames(1, 100.0, 500).expect_err("past");
        assert!(err.to_string().contains("frames 1 to 500"), "{err}");
        assert!(err.to_string().starts_with("end = 600"), "{err}");
        let err = range("0", "").frames(1, 100.0, 500).expect_err("before");
        assert!(err.to_string().starts_with("start = 0"), "{err}");
        let err = range("3s", "").frames(1, 100.0, 100).expect_err("past");
        assert!(err.to_string().contains("(0.990 s at 100 Hz)"), "{err}");
        let err = range("2s", "101").frames(1, 100.0, 500).expect_err("mixed");
        assert!(matches!(err, RangeError::EndBeforeStart { .. }), "{err}");
        assert!(range("300", "101").check_order().is_err());
        assert!(range("2s", "101").check_order().is_ok());
        assert_eq!(range("101", "101").frames(1, 100.0, 500), Ok(100..101));
    }

    #[test]
    fn toml_reads_integers_as_frames_and_strings_as_either() {
        #[derive(Deserialize, Serialize)]
        struct T {
            at: FrameOrTime,
        }
        let read = |text: &str| toml::from_str::<T>(text).map(|t| t.at);
        assert_eq!(read("at = 240").ok(), Some(FrameOrTime::Frame(240)));
        assert_eq!(read("at = \"240\"").ok(), Some(FrameOrTime::Frame(240)));
        assert_eq!(read("at = \"2.5s\"").ok(), Some(FrameOrTime::Seconds(2.5)));
        let err = read("at = 2.5").expect_err("a bare float");
        assert!(err.to_string().contains("\"2.5s\""), "{err}");
        assert!(read("at = \"soon\"").is_err());
        for at in [FrameOrTime::Frame(-3), FrameOrTime::Seconds(1.25)] {
            let text = toml::to_string(&T { at }).expect("writes");
            assert_eq!(read(&text).ok(), Some(at), "{text}");
        }
        assert!("2.5x".parse::<FrameOrTime>().is_err());
        assert!("-1s".parse::<FrameOrTime>().is_err());
    }
}
