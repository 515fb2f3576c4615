//! QTM's `Timecode` component and emoshift's frame time, both ways: SMPTE is SMPTE (QTM sends
//! no rate), IRIG is IRIG, and the cameras' clock (which no other output can say) is dropped.

use super::data::Timecode;
use crate::{FrameTime, Irig, Smpte};

impl Timecode {
    /// The timecode to send for `time`: its SMPTE timecode, else its IRIG time, else none.
    /// A subframe over QTM's 9 bits is clamped.
    pub fn from_frame_time(time: &FrameTime) -> Option<Timecode> {
        if let Some(t) = time.timecode {
            return Some(Timecode::Smpte {
                hours: t.hours,
                minutes: t.minutes,
                seconds: t.seconds,
                frames: t.frames,
                subframes: t.subframe.min(0x1ff) as u16,
            });
        }
        time.irig.map(|t| Timecode::Irig {
            years: t.year,
            days: t.day,
            hours: t.hours,
            minutes: t.minutes,
            seconds: t.seconds,
            tenths: t.tenths,
        })
    }

    /// Writes this timecode into `time` (SMPTE into `timecode` with no rate, IRIG into
    /// `irig`); camera time leaves `time` as it is.
    pub fn set_frame_time(self, time: &mut FrameTime) {
        match self {
            Timecode::Smpte {
                hours,
                minutes,
                seconds,
                frames,
                subframes,
            } => {
                time.timecode = Some(Smpte {
                    hours,
                    minutes,
                    seconds,
                    frames,
                    subframe: u32::from(subframes),
                    rate: None,
                });
            }
            Timecode::Irig {
                years,
                days,
                hours,
                minutes,
                seconds,
                tenths,
            } => {
                time.irig = Some(Irig {
                    year: years,
                    day: days,
                    hours,
                    minutes,
                    seconds,
                    tenths,
                });
            }
            Timecode::CameraTime(_) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 32: IRIG from QTM is IRIG in the frame and IRIG out again; SMPTE likewise.
    #[test]
    fn smpte_and_irig_survive_the_frame_time() {
        let irig = Timecode::Irig {
            years: 26,
            days: 332,
            hours: 9,
            minutes: 14,
            seconds: 59,
            tenths: 7,
        };
        let smpte = Timecode::Smpte {
            hours: 10,
            minutes: 0,
            seconds: 1,
            frames: 29,
            subframes: 3,
        };
        for t in [irig, smpte] {
            let mut time = FrameTime::default();
            t.set_frame_time(&mut time);
            assert_eq!(Timecode::from_frame_time(&time), Some(t));
        }
        let mut time = FrameTime::default();
        Timecode::CameraTime(7).set_frame_time(&mut time);
        assert_eq!(time, FrameTime::default());
        assert_eq!(Timecode::from_frame_time(&time), None);
    }
}
