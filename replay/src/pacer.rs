//! The replay schedule: when to send each frame of a take and when to resend its labels, as a
//! sans-IO state machine driven by an explicit clock.
//!
//! The caller owns the clock, the socket and the sleeping. [`Pacer::poll`] takes the time since
//! any fixed origin and returns one [`Action`]; the caller performs it and polls again:
//!
//! ```
//! use std::time::Duration;
//! use replay::pacer::{Action, Pacer, PacerOptions};
//!
//! let mut pacer = Pacer::new(100.0, 3, PacerOptions::default()).expect("valid schedule");
//! let mut now = Duration::ZERO; // a fake clock; a real caller reads an Instant
//! let mut sent = Vec::new();
//! loop {
//!     match pacer.poll(now) {
//!         Action::SendLabels => {}
//!         Action::SendFrame(f) => sent.push(f.frame_number),
//!         Action::Sleep { until } => now = until,
//!         Action::Done => break,
//!     }
//! }
//! assert_eq!(sent, [0, 1, 2]);
//! assert_eq!(pacer.summary().late_frames, 0);
//! ```
//!
//! # Schedule
//!
//! - The schedule starts at the first poll's `now`. Stream position `k` (0 for the first frame
//!   sent) is due at `start + k × period / speed`, computed from `k` each time, never by adding
//!   periods, so there is no drift however long the replay runs.
//! - Labels are due at the start and then every second of the caller's clock (not scaled by
//!   speed: they exist so late joiners learn the layout). When both are due, labels go first.
//!   After a stall, one label send covers every missed second.
//! - The first frame sent is take index `start_frame`. With `looping`, the index wraps to 0 after
//!   the last frame, and the stream continues.
//!
//! # Frame numbers and capture times
//!
//! A frame's *stream index* is `loop × frames + index`. Its frame number is
//! `first_frame_number + stream index`, so numbers keep increasing across loops and a receiver
//! that drops older frames never mistakes a new loop for a stale packet. Its capture time is
//! the stream index in take time, `stream index × 1e6 / rate_hz` µs: the take's first frame is
//! 0, and each loop adds the take's duration. It is independent of `speed`, like the timestamps a
//! live source capturing this take would stamp.
//!
//! # Lateness and catch-up
//!
//! Lateness is measured at the poll that releases a frame: `now − due`. A frame released more
//! than [`PacerOptions::late_after`] after its deadline counts as late. A late poll sends the due
//! frame at once; if more than [`PacerOptions::max_behind_frames`] further frames are overdue
//! too (a stalled sender), the pacer skips to the newest overdue frame instead of sending a
//! burst, and counts the frames it skipped. Their frame numbers are skipped too, exactly as a live
//! source that lost frames would look. Up to `max_behind_frames` overdue frames are sent back to
//! back, so a short hiccup loses nothing.

use std::time::Duration;

/// Default [`PacerOptions::late_after`]: 500 µs.
pub const DEFAULT_LATE_AFTER: Duration = Duration::from_micros(500);
/// Default [`PacerOptions::max_behind_frames`]: 30 frames (250 ms at 120 Hz).
pub const DEFAULT_MAX_BEHIND_FRAMES: u64 = 30;
/// Interval between label sends.
pub const LABELS_INTERVAL: Duration = Duration::from_secs(1);

/// How to replay: speed, looping, where to start, how to count lateness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PacerOptions {
    /// Playback speed: 2.0 sends twice as fast (half the period). Positive and finite.
    pub speed: f64,
    /// Start again from take index 0 after the last frame, forever.
    pub looping: bool,
    /// Take index (0-based) of the first frame sent.
    pub start_frame: usize,
    /// Frame number of take index 0 (usually [`crate::Take::first_frame`]).
    pub first_frame_number: i64,
    /// A frame released later than this after its deadline counts as late.
    pub late_after: Duration,
    /// Overdue frames sent back to back before the pacer skips to the present instead.
    pub max_behind_frames: u64,
}

impl Default for PacerOptions {
    fn default() -> Self {
        PacerOptions {
            speed: 1.0,
            looping: false,
            start_frame: 0,
            first_frame_number: 0,
            late_after: DEFAULT_LATE_AFTER,
            max_behind_frames: DEFAULT_MAX_BEHIND_FRAMES,
        }
    }
}

/// Why a schedule cannot be built.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum PacerError {
    /// The frame rate is not positive and finite.
    #[error("frame rate must be positive and finite, got {0}")]
    BadRate(f64),
    /// The speed is not positive and finite.
    #[error("speed must be positive and finite, got {0}")]
    BadSpeed(f64),
    /// The take has no frames.
    #[error("the take has no frames to send")]
    NoFrames,
    /// The start frame is past the end of the take.
    #[error("start frame {start} is past the last frame index {last}")]
    StartPastEnd {
        /// The requested start index.
        start: usize,
        /// The last valid index.
        last: usize,
    },
}

/// One frame to send now.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameSend {
    /// Take index (0-based) of the frame's data.
    pub index: usize,
    /// `loop × frames + index`: the position in the endless stream.
    pub stream_index: u64,
    /// Frame number to put on the wire (see the module docs).
    pub frame_number: i64,
    /// Capture time, µs of take time (see the module docs).
    pub capture_time_us: i64,
    /// When the frame was due, on the caller's clock.
    pub due: Duration,
    /// `now − due` at release (zero when early or on time).
    pub lateness: Duration,
}

/// What the caller should do next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Action {
    /// Send the labels message now, then poll again.
    SendLabels,
    /// Send this frame now, then poll again.
    SendFrame(FrameSend),
    /// Nothing is due before `until` (caller's clock); wait, then poll again.
    Sleep {
        /// The next deadline.
        until: Duration,
    },
    /// The take is over (never with `looping`).
    Done,
}

/// What a replay did, for its summary line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PacerSummary {
    /// Frames released.
    pub frames_sent: u64,
    /// Label messages released.
    pub labels_sent: u64,
    /// Frames released more than `late_after` after their deadline.
    pub late_frames: u64,
    /// Frames skipped to catch up after a stall (never sent).
    pub skipped_frames: u64,
    /// The largest lateness of any frame released.
    pub max_lateness: Duration,
    /// Sum of the lateness of every frame released (for a mean).
    pub total_lateness: Duration,
}

/// The replay schedule of one take. See the module docs for the call order and the rules.
#[derive(Debug, Clone)]
pub struct Pacer {
    frames: usize,
    rate_hz: f64,
    /// Nanoseconds between frames on the caller's clock (period / speed).
    period_ns: f64,
    options: PacerOptions,
    start: Option<Duration>,
    /// Position of the next frame, counted from the first frame sent (0).
    next: u64,
    /// Label sends due so far: the next is due at `start + labels_due × 1 s`.
    labels_due: u64,
    summary: PacerSummary,
}

impl Pacer {
    /// A schedule for `frames` frames at `rate_hz`.
    ///
    /// # Errors
    /// [`PacerError`] for a rate or speed that is not positive and finite, no frames, or a start
    /// frame past the end.
    pub fn new(rate_hz: f64, frames: usize, options: PacerOptions) -> Result<Pacer, PacerError> {
        if !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Err(PacerError::BadRate(rate_hz));
        }
        if !(options.speed.is_finite() && options.speed > 0.0) {
            return Err(PacerError::BadSpeed(options.speed));
        }
        if frames == 0 {
            return Err(PacerError::NoFrames);
        }
        if options.start_frame >= frames {
            return Err(PacerError::StartPastEnd {
                start: options.start_frame,
                last: frames - 1,
            });
        }
        Ok(Pacer {
            frames,
            rate_hz,
            period_ns: 1e9 / (rate_hz * options.speed),
            options,
            start: None,
            next: 0,
            labels_due: 0,
            summary: PacerSummary::default(),
        })
    }

    /// The next thing to do at `now` (time since any fixed origin; it must not go backwards).
    /// The first call starts the schedule.
    pub fn poll(&mut self, now: Duration) -> Action {
        let start = *self.start.get_or_insert(now);
        if self.finished() {
            return Action::Done;
        }
        let labels_at = start + LABELS_INTERVAL * self.labels_due_u32();
        if now >= labels_at {
            // One send covers every second missed during a stall.
            let elapsed = now.saturating_sub(start).as_nanos() / LABELS_INTERVAL.as_nanos();
            self.labels_due = u64::try_from(elapsed).unwrap_or(u64::MAX).saturating_add(1);
            self.summary.labels_sent += 1;
            return Action::SendLabels;
        }
        let due = self.due(self.next);
        if now < due {
            return Action::Sleep {
                until: due.min(labels_at),
            };
        }
        self.catch_up(now);
        if self.finished() {
            return Action::Done;
        }
        Action::SendFrame(self.release(now))
    }

    /// When stream position `k` is due: computed from `k`, so errors never accumulate.
    fn due(&self, k: u64) -> Duration {
        let start = self.start.unwrap_or_default();
        start + Duration::from_nanos((k as f64 * self.period_ns).round() as u64)
    }

    /// `labels_due` as a multiplier of the interval; a replay would need 136 years to overflow.
    fn labels_due_u32(&self) -> u32 {
        u32::try_from(self.labels_due).unwrap_or(u32::MAX)
    }

    /// Skips to the newest overdue frame when more than `max_behind_frames` are overdue.
    fn catch_up(&mut self, now: Duration) {
        let late_ns = now.saturating_sub(self.due(self.next)).as_nanos() as f64;
        let behind = (late_ns / self.period_ns).floor() as u64;
        if behind > self.options.max_behind_frames {
            let skip = match self.remaining() {
                Some(left) => behind.min(left),
                None => behind,
            };
            self.next += skip;
            self.summary.skipped_frames += skip;
        }
    }

    /// Frames left to send, `None` when looping.
    fn remaining(&self) -> Option<u64> {
        if self.options.looping {
            return None;
        }
        Some((self.frames - self.options.start_frame) as u64 - self.next)
    }

    fn finished(&self) -> bool {
        self.remaining() == Some(0)
    }

    /// Releases position `next` at `now` and accounts its lateness.
    fn release(&mut self, now: Duration) -> FrameSend {
        let due = self.due(self.next);
        let stream_index = self.options.start_frame as u64 + self.next;
        let lateness = now.saturating_sub(due);
        self.next += 1;
        let s = &mut self.summary;
        s.frames_sent += 1;
        s.max_lateness = s.max_lateness.max(lateness);
        s.total_lateness += lateness;
        if lateness > self.options.late_after {
            s.late_frames += 1;
        }
        FrameSend {
            index: (stream_index % self.frames as u64) as usize,
            stream_index,
            frame_number: self
                .options
                .first_frame_number
                .saturating_add(i64::try_from(stream_index).unwrap_or(i64::MAX)),
            capture_time_us: (stream_index as f64 * 1e6 / self.rate_hz).round() as i64,
            due,
            lateness,
        }
    }

    /// What the replay did so far.
    pub fn summary(&self) -> PacerSummary {
        self.summary
    }

    /// The options the schedule was built with.
    pub fn options(&self) -> &PacerOptions {
        &self.options
    }
}
