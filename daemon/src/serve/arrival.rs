//! When the processing thread should poll for the next frame instead of parking, sans-IO.
//!
//! Waking a parked thread costs 30-50 µs on a virtual machine (the idle CPU must be
//! interrupted and rescheduled), more than the whole frame path. But a stage sends on a steady
//! clock (cameras are genlocked), so the next frame's arrival is predictable. The thread
//! parks until [`SpinWindow::lead`] before it and then polls its socket and queue until it comes,
//! or until [`SpinWindow::grace`] after it; anything off the beat is received the ordinary
//! way. The window is skipped when it would take more than [`MAX_DUTY`] of the period, so
//! unsteady or interleaved sources cost no CPU.
//!
//! Call order: [`ArrivalClock::frame_arrived`] with each frame's receive time,
//! [`ArrivalClock::plan`] whenever the queue is empty.

use std::time::{Duration, Instant};

/// Frames closer than this to the first frame of a burst belong to it (several performers
/// sent on the same tick).
pub const BURST: Duration = Duration::from_millis(1);
/// Periods outside this range are not a capture rate (a pause, a restart): ignored.
pub const PERIODS: (Duration, Duration) = (Duration::from_millis(2), Duration::from_millis(50));
/// The polling window may take at most this share of the period.
pub const MAX_DUTY: f64 = 0.1;

/// How long to poll around the expected arrival.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SpinWindow {
    /// Polling starts this long before the expected arrival (covers a timed wake-up's
    /// lateness); zero turns polling off.
    pub lead: Duration,
    /// ... and lasts until this long after it (covers the source's jitter).
    pub grace: Duration,
}

impl SpinWindow {
    /// Polling off: always park.
    pub const OFF: SpinWindow = SpinWindow {
        lead: Duration::ZERO,
        grace: Duration::ZERO,
    };
}

/// What the processing thread should do while its queue is empty.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wait {
    /// Park until a frame or a command comes.
    Park,
    /// Park, but wake by this instant to start polling.
    ParkUntil(Instant),
    /// Poll the queue until this instant.
    PollUntil(Instant),
}

/// Gaps between ticks remembered; the period is their median, which ignores a stray gap
/// (a start-up delay, a dropped frame) where an average would take many ticks to forget it.
const GAPS: usize = 8;

/// The beat of the incoming frames. See the module docs.
#[derive(Debug, Clone)]
pub struct ArrivalClock {
    window: SpinWindow,
    burst_start: Option<Instant>,
    gaps: [Duration; GAPS],
    gap_count: usize,
    period: Option<Duration>,
}

impl ArrivalClock {
    /// A clock polling within `window`.
    pub fn new(window: SpinWindow) -> ArrivalClock {
        ArrivalClock {
            window,
            burst_start: None,
            gaps: [Duration::ZERO; GAPS],
            gap_count: 0,
            period: None,
        }
    }

    /// The period learned so far.
    pub fn period(&self) -> Option<Duration> {
        self.period
    }

    /// When the current tick's burst is over.
    pub fn burst_end(&self) -> Option<Instant> {
        self.burst_start.map(|start| start + BURST)
    }

    /// A frame was received at `at`.
    pub fn frame_arrived(&mut self, at: Instant) {
        let Some(start) = self.burst_start else {
            self.burst_start = Some(at);
            return;
        };
        let gap = at.saturating_duration_since(start);
        if gap < BURST {
            return;
        }
        self.burst_start = Some(at);
        if gap < PERIODS.0 || gap > PERIODS.1 {
            return;
        }
        self.gaps[self.gap_count % GAPS] = gap;
        self.gap_count += 1;
        let mut recent = self.gaps;
        let recent = &mut recent[..self.gap_count.min(GAPS)];
        recent.sort_unstable();
        self.period = Some(recent[recent.len() / 2]);
    }

    /// How to wait at `now` with an empty queue.
    pub fn plan(&self, now: Instant) -> Wait {
        let (Some(start), Some(period)) = (self.burst_start, self.period) else {
            return Wait::Park;
        };
        let SpinWindow { lead, grace } = self.window;
        if lead.is_zero() || (lead + grace).as_secs_f64() > period.as_secs_f64() * MAX_DUTY {
            return Wait::Park;
        }
        let expected = start + period;
        if now + lead < expected {
            Wait::ParkUntil(expected - lead)
        } else if now < expected + grace {
            Wait::PollUntil(expected + grace)
        } else {
            Wait::Park
        }
    }
}

#[cfg(test)]
mod tests;
