//! The page's health view: the daemon's counters ([`Stats`], what `/status` answers) as one
//! JSON text, with latency percentiles over the last few seconds as well as since the start
//! (a jump shows at once, not diluted by an hour of good frames).

use std::collections::VecDeque;

use hdrhistogram::Histogram;
use serde_json::{json, Value};

use crate::serve::stats::{MonitorCounters, Stats, SubscriberStatus};
use engine::StreamStatus;

/// Seconds the recent latency window spans.
pub(crate) const WINDOW_S: usize = 5;

/// The latency histograms since the start, kept once a second for the recent window.
#[derive(Debug, Default)]
pub(crate) struct Latency {
    /// (processed, sent) since the start, oldest first, one a second.
    ring: VecDeque<(Histogram<u64>, Histogram<u64>)>,
    /// The percentiles last computed.
    last: Value,
}

impl Latency {
    /// Keeps this second's histograms (copied out under the stats lock by the caller) and
    /// computes the percentiles.
    pub(crate) fn observe(&mut self, processed: Histogram<u64>, sent: Histogram<u64>) {
        if self.ring.len() > WINDOW_S {
            self.ring.pop_front();
        }
        self.ring.push_back((processed, sent));
        let (Some(first), Some(now)) = (self.ring.front(), self.ring.back()) else {
            return;
        };
        let stage = |old: &Histogram<u64>, now: &Histogram<u64>| {
            let mut recent = now.clone();
            // Counts only grow, so the older copy subtracts; if not, show the whole.
            if recent.subtract(old).is_err() {
                recent = now.clone();
            }
            let q = |h: &Histogram<u64>, q: f64| h.value_at_quantile(q);
            json!({
                "p50": q(&recent, 0.5), "p99": q(&recent, 0.99), "max": recent.max(),
                "n": recent.len(),
                "p50_all": q(now, 0.5), "p99_all": q(now, 0.99), "max_all": now.max(),
            })
        };
        self.last = json!({
            "window_s": self.ring.len().saturating_sub(1),
            "processed": stage(&first.0, &now.0),
            "sent": stage(&first.1, &now.1),
        });
    }

    /// The percentiles last computed.
    pub(crate) fn value(&self) -> &Value {
        &self.last
    }
}

/// What the health view shows, copied out of the stats under its lock.
#[derive(Debug)]
pub(crate) struct Health {
    value: Value,
}

impl Health {
    /// Copies the counters out (quick: no percentile is computed under the lock).
    pub(crate) fn of(s: &Stats) -> Health {
        let (c, i) = (&s.counters, s.input());
        let value = json!({
            "model": s.model,
            "frames_in": i.frames_in,
            "frames_out": c.frames_out,
            "drops": {
                "queue_full": c.dropped_queue_full,
                "duplicate": c.dropped_duplicate,
                "stale": c.dropped_stale,
                "no_layout": i.dropped_no_layout,
                "unmatched": c.dropped_unmatched,
                "not_allowed": s.dropped_not_allowed,
                "bad_packets": i.bad_total(),
                "send_buffer": s.send.dropped_send_buffer,
                "send_errors": s.send.send_errors,
                "frame_errors": c.frame_errors + s.send.encode_errors,
            },
            "missing_markers": c.missing_markers,
            "glitches": c.glitches,
            "restarts": c.restarts,
            "labels_refused": i.labels_refused,
            "control_refused": s.control_refused,
            "streams": s.per_stream.iter().map(stream).collect::<Vec<_>>(),
            "subscribers": s.subscribers.iter().map(subscriber).collect::<Vec<_>>(),
            "recording": s.recording.as_ref().map(|(p, raw)| json!({"path": p, "raw": raw})),
            "recording_error": s.recording_error,
            "sources": s.sources.iter().map(|(name, pairs)| (name.to_string(), pairs_object(pairs)))
                .collect::<serde_json::Map<_, _>>(),
        });
        Health { value }
    }

    /// The `status` message, with the latencies and the monitor's own counters.
    pub(crate) fn into_message(mut self, latency: &Latency, monitor: MonitorCounters) -> String {
        self.value["type"] = json!("status");
        self.value["latency"] = latency.value().clone();
        self.value["monitor"] = json!({
            "viewers": monitor.viewers,
            "dropped": monitor.dropped,
            "unpublished": monitor.unpublished,
            "refused": monitor.refused,
        });
        self.value.to_string()
    }
}

fn stream(st: &StreamStatus) -> Value {
    json!({
        "id": st.id,
        "name": st.name,
        "source": format!("{}/{}", st.key.source, st.key.layout_id),
        "performer": st.performer,
        "model_markers": st.model_markers,
        "matched_markers": st.model_markers - st.unmatched_markers.min(st.model_markers),
        "target": st.target,
        "amount": st.amount,
        "frames": st.frames,
        "duplicates": st.duplicates,
        "stale": st.stale,
    })
}

/// A source's (or the NatNet server's) own status pairs as one object, by name.
fn pairs_object(pairs: &[(String, protocol::StatusValue)]) -> Value {
    let object = pairs.iter().map(|(k, v)| {
        let v = match v {
            protocol::StatusValue::Int(i) => json!(i),
            protocol::StatusValue::Text(t) => json!(t),
        };
        (k.clone(), v)
    });
    Value::Object(object.collect())
}

fn subscriber(sub: &SubscriberStatus) -> Value {
    json!({
        "address": sub.addr.to_string(),
        "profile": sub.profile.as_str(),
        "performer": sub.performer,
        "lease_ms": sub.lease_ms,
        "sends": sub.sends,
        "failures": sub.failures,
        "backing_off": sub.backing_off,
    })
}

#[cfg(test)]
mod tests;
