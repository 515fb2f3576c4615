//! A frame or time range of a take (`--start`/`--end` of `convert`): rest before and after a
//! sentence trimmed off without another tool (issue 37).

use std::ops::Range;

use anyhow::{bail, Result};
use replay::Take;

pub use replay::session::FrameOrTime;

/// A range as frame indices from a take's first frame, `from..to`, before the take's length is
/// known (a streamed take): `to` is `None` without `--end`. [`Cut::check`] refuses what keeps
/// nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Cut {
    /// The first frame kept.
    pub from: usize,
    /// The frame after the last kept (`None`: to the end).
    pub to: Option<usize>,
}

impl Cut {
    /// The cut `start`..=`end` of a take whose first frame is `first_frame`, at `rate_hz`.
    pub fn new(
        (first_frame, rate_hz): (i64, f64),
        start: Option<FrameOrTime>,
        end: Option<FrameOrTime>,
    ) -> Cut {
        let from = start.map_or(0, |s| s.index(first_frame, rate_hz)).max(0) as usize;
        let to = end.map(|e| (e.index(first_frame, rate_hz) + 1).max(0) as usize);
        Cut { from, to }
    }

    /// Whether frame index `f` is kept.
    pub fn keeps(&self, f: usize) -> bool {
        f >= self.from && self.to.is_none_or(|to| f < to)
    }

    /// Whether no frame at index `f` or later is kept (a streamed take may stop reading).
    pub fn is_past(&self, f: usize) -> bool {
        self.to.is_some_and(|to| f >= to)
    }

    /// The frames kept of a take of `frames` frames (`None`: not known yet).
    ///
    /// # Errors
    /// A cut that keeps no frame (of the take, when its length is known), naming the take's own
    /// range and what to write.
    pub fn check(&self, take: Span, frames: Option<usize>) -> Result<Option<Range<usize>>> {
        let to = match (self.to, frames) {
            (Some(to), Some(n)) => Some(to.min(n)),
            (to, n) => to.or(n),
        };
        let from = match frames {
            Some(n) => self.from.min(n),
            None => self.from,
        };
        if to.is_some_and(|to| from >= to) {
            bail!("{}", take.nothing_kept(frames));
        }
        Ok(frames.map(|_| from..to.unwrap_or(from)))
    }
}

/// What a take's frames are numbered and timed by: its first frame number and rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Span {
    /// The first frame's number.
    pub first_frame: i64,
    /// Frames per second.
    pub rate_hz: f64,
}

impl Span {
    /// `--start/--end keep no frame: the take has frames 1 to 500 (4.990 s at 100 Hz); give a
    /// start before its end, within those` (without `frames`, its first frame only).
    pub fn nothing_kept(&self, frames: Option<usize>) -> String {
        let first = self.first_frame;
        let what = match frames {
            Some(n) => format!(
                "the take has frames {first} to {} ({:.3} s at {} Hz)",
                first + n as i64 - 1,
                n.saturating_sub(1) as f64 / self.rate_hz,
                self.rate_hz
            ),
            None => format!("the take starts at frame {first} ({} Hz)", self.rate_hz),
        };
        format!(
            "--start/--end keep no frame: {what}; give a frame number or a time (2.5s) from \
             there, the start before the end"
        )
    }
}

/// The frame indices from `start` to `end` inclusive (the whole take without either).
///
/// # Errors
/// A range that keeps no frame of the take, naming the take's own range.
pub fn frame_range(
    take: &Take,
    start: Option<FrameOrTime>,
    end: Option<FrameOrTime>,
) -> Result<Range<usize>> {
    let span = Span {
        first_frame: take.first_frame,
        rate_hz: take.rate_hz,
    };
    let cut = Cut::new((take.first_frame, take.rate_hz), start, end);
    let range = cut.check(span, Some(take.n_frames()))?;
    Ok(range.expect("the take's length is known"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn take(frames: usize) -> Take {
        let mut t = Take::new(vec!["a".into()], 100.0, 1);
        for i in 0..frames {
            t.push_frame(&[i as f32, 0.0, 0.0], &[false]);
        }
        t
    }

    #[test]
    fn frames_and_times_name_the_same_cut() {
        let t = take(500);
        let by_frame = frame_range(&t, "101".parse().ok(), "300".parse().ok()).expect("ok");
        let by_time = frame_range(&t, "1s".parse().ok(), "2.99s".parse().ok()).expect("ok");
        assert_eq!((by_frame.clone(), by_time), (100..300, 100..300));
        let mut cut = t.clone();
        cut.keep_frames(by_frame);
        assert_eq!((cut.n_frames(), cut.first_frame), (200, 101));
        assert_eq!(cut.frame(0), &[100.0, 0.0, 0.0]);
        assert_eq!(frame_range(&t, None, None).expect("all"), 0..500);
    }

    #[test]
    fn an_empty_or_unreadable_range_is_refused() {
        let t = take(10);
        let err = frame_range(&t, "20".parse().ok(), None).expect_err("past the end");
        assert!(err.to_string().contains("frames 1 to 10"), "{err}");
    }
}
