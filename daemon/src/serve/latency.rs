//! End-to-end latency per stream, from the source's capture time to the frame processed,
//! "when the clocks allow": a NatNet frame's mid-exposure through the echo's clock offset, an
//! OSC frame whose `/mocap/timecode` says its capture time is UTC against the system clock.
//! Other frames (a source's own clock of unknown epoch) are not measured.

use std::time::{Instant, SystemTime, UNIX_EPOCH};

use hdrhistogram::Histogram;
use protocol::CaptureClock;

use super::natnet::Session;
use super::stats::Stats;
use crate::engine::pipeline::Emitted;

/// Per stream id, capture → processed in µs, since the last merge.
#[derive(Debug, Default)]
pub(crate) struct StreamLatency {
    streams: Vec<(i32, Histogram<u64>)>,
}

impl StreamLatency {
    /// Records frame `e` processed at `processed`, when its capture time can be placed on
    /// this host's clocks. Allocates only for a stream's first measured frame.
    pub(crate) fn record(&mut self, e: &Emitted<'_>, natnet: Option<&Session>, processed: Instant) {
        let capture_us = e.input.header().capture_time_us;
        let us = match (natnet, e.time.clock) {
            (Some(s), _) => s
                .local_instant(capture_us)
                .and_then(|at| processed.checked_duration_since(at))
                .map(|d| d.as_micros() as i64),
            (None, CaptureClock::Utc) => SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .ok()
                .map(|now| now.as_micros() as i64 - capture_us),
            (None, CaptureClock::Source) => None,
        };
        // A negative latency means the clocks disagree: nothing to say.
        let Some(us) = us.filter(|&us| us >= 0) else {
            return;
        };
        let id = e.identity.id;
        let h = match self.streams.iter().position(|(s, _)| *s == id) {
            Some(i) => &mut self.streams[i].1,
            None => {
                self.streams.push((id, Stats::histogram()));
                &mut self.streams.last_mut().expect("just pushed").1
            }
        };
        Stats::record(h, us as u64);
    }

    /// Adds what was measured into the shared stats' histograms and starts over.
    pub(crate) fn merge_into(&mut self, shared: &mut Vec<(i32, Histogram<u64>)>) {
        for (id, h) in &mut self.streams {
            if h.is_empty() {
                continue;
            }
            match shared.iter_mut().find(|(s, _)| s == id) {
                // Same bounds on both sides, so adding never fails.
                Some((_, total)) => drop(total.add(&*h)),
                None => shared.push((*id, h.clone())),
            }
            h.reset();
        }
    }
}
