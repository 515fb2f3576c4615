//! How the processing thread waits while nothing is waiting: parked in its [`super::Inbox`],
//! or polling it around a steady source's next expected frame ([`super::ArrivalClock`]).

use std::time::{Duration, Instant};

use super::{Processing, IDLE, MERGE_EVERY, QUIET};
use crate::serve::arrival::Wait;

/// What the processing thread does while its queue is empty.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Next {
    /// Wait up to this long for a frame or a command; a timeout means nothing came for a
    /// while, a good moment to tidy.
    WaitIdle(Duration),
    /// Wait up to this long: a planned wake-up before the next beat, nothing to tidy.
    WaitBeat(Duration),
    /// The counters were merged in the gap before the next tick; plan again.
    PlanAgain,
}

impl Processing {
    /// How long to wait for the next frame or command (polling first when a beat is due).
    pub(super) fn plan_wait(&mut self) -> Next {
        if !self.queue.frames.is_empty() || self.inbox.pending() {
            return Next::WaitBeat(Duration::ZERO);
        }
        let now = Instant::now();
        match self.arrival.plan(now) {
            Wait::PollUntil(until) => {
                if self.poll_until(until) {
                    self.poll_hits += 1;
                } else {
                    self.poll_misses += 1;
                }
                Next::WaitIdle(IDLE)
            }
            Wait::ParkUntil(at) => {
                let due = self.last_merge.elapsed() >= MERGE_EVERY && at - now > QUIET;
                match self.arrival.burst_end() {
                    // Merge in the gap, once this tick's frames are all in.
                    Some(end) if due && end > now => Next::WaitBeat((end - now).min(at - now)),
                    _ if due && self.cmd_rx.is_empty() => {
                        self.tidy();
                        Next::PlanAgain
                    }
                    _ => Next::WaitBeat((at - now).min(IDLE)),
                }
            }
            Wait::Park => Next::WaitIdle(IDLE),
        }
    }

    /// Polls the socket and the queues until something comes or `until`; `true` when a frame
    /// came. No `spin_loop` hint: a hypervisor may take a run of PAUSE instructions as lock
    /// contention and deschedule the CPU.
    fn poll_until(&mut self, until: Instant) -> bool {
        loop {
            let rang = self.inbox.wait(Duration::ZERO);
            if !self.queue.frames.is_empty() || (rang && self.cmd_rx.is_empty()) {
                return true;
            }
            if !self.cmd_rx.is_empty() || Instant::now() >= until {
                return false;
            }
        }
    }
}
