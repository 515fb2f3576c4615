//! Latency histograms: the one histogram shape every stage uses, and end-to-end latency per
//! stream, from the source's capture time to the frame processed, "when the clocks allow": the
//! source places its capture time on this host's clock ([`crate::serve::sources::Arrival`]:
//! a NatNet frame's mid-exposure through the echo's clock offset, an OSC frame stamped UTC);
//! other frames (a source's own clock of unknown epoch) are not measured.

use std::time::Instant;

use hdrhistogram::Histogram;

/// An empty latency histogram, 1 µs to 60 s at 3 significant digits.
pub fn histogram() -> Histogram<u64> {
    Histogram::new_with_bounds(1, 60_000_000, 3).expect("constant bounds are valid")
}

/// Records one latency in microseconds, saturating at the histogram's top.
pub fn record(h: &mut Histogram<u64>, us: u64) {
    h.saturating_record(us.max(1));
}

/// Per stream id, capture → processed in µs, since the last merge.
#[derive(Debug, Default)]
pub(crate) struct StreamLatency {
    streams: Vec<(i32, Histogram<u64>)>,
}

impl StreamLatency {
    /// Records a frame of stream `id` captured at `captured` (this host's clock) and processed
    /// at `processed`. Allocates only for a stream's first measured frame.
    pub(crate) fn record(&mut self, id: i32, captured: Option<Instant>, processed: Instant) {
        // Captured after processed means the clocks disagree: nothing to say.
        let Some(d) = captured.and_then(|at| processed.checked_duration_since(at)) else {
            return;
        };
        let h = match self.streams.iter().position(|(s, _)| *s == id) {
            Some(i) => &mut self.streams[i].1,
            None => {
                self.streams.push((id, histogram()));
                &mut self.streams.last_mut().expect("just pushed").1
            }
        };
        record(h, d.as_micros() as u64);
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
