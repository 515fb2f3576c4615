//! IRIG time of day, as QTM sends it when its cameras are synchronised to an IRIG clock.

use std::fmt;

/// An IRIG time stamp: the year (two digits), the day of the year, the time of day and tenths
/// of a second. Unlike [`super::Smpte`] it counts no frames and has no rate: it is a wall-clock
/// time, so outputs that only carry SMPTE (NatNet, `/mocap/timecode`) cannot say it without
/// inventing a frame rate, and do not.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Irig {
    /// Year of the century, 0..100.
    pub year: u8,
    /// Day of the year, 1..=366.
    pub day: u16,
    /// Hours, 0..24.
    pub hours: u8,
    /// Minutes, 0..60.
    pub minutes: u8,
    /// Seconds, 0..60.
    pub seconds: u8,
    /// Tenths of a second, 0..10.
    pub tenths: u8,
}

impl Irig {
    /// Whether every field is in range.
    pub fn is_valid(&self) -> bool {
        self.year < 100
            && (1..=366).contains(&self.day)
            && self.hours < 24
            && self.minutes < 60
            && self.seconds < 60
            && self.tenths < 10
    }
}

/// `yy:ddd:hh:mm:ss.t`, the order IRIG counts in.
impl fmt::Display for Irig {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:02}:{:03}:{:02}:{:02}:{:02}.{}",
            self.year, self.day, self.hours, self.minutes, self.seconds, self.tenths
        )
    }
}
