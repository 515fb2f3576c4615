//! Counters and per-stage latency histograms (received → processed → sent), logged every few
//! seconds and sent as the `/status` reply.

use hdrhistogram::Histogram;
use protocol::DecodeErrorKind;

use crate::engine::{Counters, StreamStatus};

/// Counters of sending.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SendCounters {
    /// Datagrams sent.
    pub datagrams_sent: u64,
    /// Sends that failed.
    pub send_errors: u64,
    /// Subscribers dropped after repeated failures.
    pub clients_dropped: u64,
    /// Datagrams not sent because the socket's send buffer was full.
    pub dropped_send_buffer: u64,
}

/// Everything `/status` reports, merged from the processing thread.
#[derive(Debug)]
pub struct Stats {
    /// Processing counters (latest snapshot).
    pub counters: Counters,
    /// Sender counters.
    pub send: SendCounters,
    /// Received → processed, microseconds.
    pub processed_us: Histogram<u64>,
    /// Processed → sent (to the last subscriber), microseconds.
    pub sent_us: Histogram<u64>,
    /// Subscribers now.
    pub clients: u64,
    /// Streams now.
    pub streams: u64,
    /// Polling windows in which a frame came (it was processed without a wake-up).
    pub poll_hits: u64,
    /// Polling windows that ended without a frame.
    pub poll_misses: u64,
    /// Each stream's counters.
    pub per_stream: Vec<StreamStatus>,
}

impl Default for Stats {
    fn default() -> Self {
        Stats::new()
    }
}

impl Stats {
    /// An empty latency histogram, 1 µs to 60 s at 3 significant digits.
    pub fn histogram() -> Histogram<u64> {
        Histogram::new_with_bounds(1, 60_000_000, 3).expect("constant bounds are valid")
    }

    /// Empty stats.
    pub fn new() -> Stats {
        Stats {
            counters: Counters::default(),
            send: SendCounters::default(),
            processed_us: Stats::histogram(),
            sent_us: Stats::histogram(),
            clients: 0,
            streams: 0,
            poll_hits: 0,
            poll_misses: 0,
            per_stream: Vec::new(),
        }
    }

    /// Records one latency in microseconds, saturating at the histogram's top.
    pub fn record(h: &mut Histogram<u64>, us: u64) {
        h.saturating_record(us.max(1));
    }

    /// `(name, value)` pairs in the order `/status/confirm` carries them.
    pub fn pairs(&self) -> Vec<(String, i64)> {
        let c = &self.counters;
        let i = |v: u64| i64::try_from(v).unwrap_or(i64::MAX);
        let mut out: Vec<(String, i64)> = [
            ("frames_in", c.frames_in),
            ("frames_out", c.frames_out),
            ("frames_dropped", c.dropped_queue_full),
            ("dropped_duplicate", c.dropped_duplicate),
            ("dropped_stale", c.dropped_stale),
            ("dropped_no_layout", c.dropped_no_layout),
            ("dropped_unmatched", c.dropped_unmatched),
            ("frame_errors", c.frame_errors),
            ("labels_in", c.labels_in),
            ("missing_markers", c.missing_markers),
            ("glitches", c.glitches),
            ("restarts", c.restarts),
            ("model_swaps", c.model_swaps),
            ("bad_packets", c.bad_total()),
            ("datagrams_sent", self.send.datagrams_sent),
            ("send_errors", self.send.send_errors),
            ("clients_dropped", self.send.clients_dropped),
            ("dropped_send_buffer", self.send.dropped_send_buffer),
            ("clients", self.clients),
            ("streams", self.streams),
            ("poll_hits", self.poll_hits),
            ("poll_misses", self.poll_misses),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), i(v)))
        .collect();
        for kind in DecodeErrorKind::ALL {
            out.push((format!("bad_{}", kind.as_str()), i(c.bad[kind.index()])));
        }
        for st in &self.per_stream {
            let name = format!("stream/{}/{}", st.key.source, st.key.layout_id);
            for (what, v) in [
                ("frames", st.frames),
                ("dropped_duplicate", st.duplicates),
                ("dropped_stale", st.stale),
            ] {
                out.push((format!("{name}/{what}"), i(v)));
            }
        }
        for (name, h) in [("processed", &self.processed_us), ("sent", &self.sent_us)] {
            for (q, label) in [(0.5, "p50"), (0.99, "p99"), (0.999, "p999")] {
                out.push((format!("{name}_{label}_us"), i(h.value_at_quantile(q))));
            }
            out.push((format!("{name}_max_us"), i(h.max())));
        }
        out
    }

    /// Logs a one-line summary.
    pub fn log(&self) {
        let c = &self.counters;
        tracing::info!(
            frames_in = c.frames_in,
            frames_out = c.frames_out,
            dropped = c.dropped_queue_full + c.dropped_stale + c.dropped_duplicate,
            bad_packets = c.bad_total(),
            missing_markers = c.missing_markers,
            clients = self.clients,
            streams = self.streams,
            processed_p99_us = self.processed_us.value_at_quantile(0.99),
            sent_p99_us = self.sent_us.value_at_quantile(0.99),
            "status"
        );
        for st in &self.per_stream {
            tracing::info!(
                source = %st.key.source,
                layout = st.key.layout_id,
                performer = st.performer.as_deref().unwrap_or("-"),
                frames = st.frames,
                dropped_duplicate = st.duplicates,
                dropped_stale = st.stale,
                "stream"
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_pairs_name_every_bad_packet_kind_and_the_percentiles() {
        let mut s = Stats::new();
        s.counters.frames_in = 3;
        s.counters.bad_packet(DecodeErrorKind::Truncated);
        Stats::record(&mut s.processed_us, 40);
        s.per_stream.push(StreamStatus {
            key: crate::engine::streams::StreamKey {
                source: "127.0.0.1:5000".parse().expect("literal address"),
                layout_id: 2,
            },
            performer: None,
            frames: 7,
            duplicates: 1,
            stale: 3,
        });
        let pairs = s.pairs();
        let get = |n: &str| pairs.iter().find(|(k, _)| k == n).map(|(_, v)| *v);
        assert_eq!(get("frames_in"), Some(3));
        assert_eq!(get("bad_packets"), Some(1));
        assert_eq!(
            get(&format!("bad_{}", DecodeErrorKind::Truncated.as_str())),
            Some(1)
        );
        assert_eq!(get("processed_p50_us"), Some(40));
        assert_eq!(get("stream/127.0.0.1:5000/2/frames"), Some(7));
        assert_eq!(get("stream/127.0.0.1:5000/2/dropped_stale"), Some(3));
    }
}
