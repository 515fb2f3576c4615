//! A frame or time range of a take (`--start`/`--end` of `convert`): rest before and after a
//! sentence trimmed off without another tool (issue 37).

use std::ops::Range;
use std::str::FromStr;

use anyhow::{bail, Result};
use replay::Take;

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

impl FrameOrTime {
    /// The 0-based frame index of `take` this names (past the end: the frame count).
    fn index(self, take: &Take) -> i64 {
        match self {
            FrameOrTime::Frame(n) => n - take.first_frame,
            FrameOrTime::Seconds(s) => (s * take.rate_hz).round() as i64,
        }
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
    let n = take.n_frames() as i64;
    let from = start.map_or(0, |s| s.index(take)).clamp(0, n);
    let to = end.map_or(n, |e| e.index(take) + 1).clamp(0, n);
    if from >= to {
        bail!(
            "--start/--end keep no frame: the take has frames {} to {} ({:.3} s at {} Hz)",
            take.first_frame,
            take.first_frame + n - 1,
            take.time_of(take.n_frames().saturating_sub(1)),
            take.rate_hz
        );
    }
    Ok(from as usize..to as usize)
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
        assert!("2.5x".parse::<FrameOrTime>().is_err());
        assert!("-1s".parse::<FrameOrTime>().is_err());
    }
}
