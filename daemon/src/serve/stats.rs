//! Counters and per-stage latency histograms (received → processed → sent), logged every few
//! seconds and sent as the `/status` reply.

use std::net::SocketAddr;
use std::sync::Arc;

use engine::{Counters, StreamStatus};
use hdrhistogram::Histogram;
use protocol::{DecodeErrorKind, Profile, StatusValue};

use super::latency;
use super::sinks::osc::SendCounters;
use super::sources::{InputCounters, InputTotals};

/// One subscriber as `/status` lists it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SubscriberStatus {
    /// Where it is sent to.
    pub addr: SocketAddr,
    /// Its profile.
    pub profile: Profile,
    /// The one performer it takes, if any.
    pub performer: Option<String>,
    /// Milliseconds left on its lease; `None` for a static target.
    pub lease_ms: Option<u64>,
    /// Frames sent to it.
    pub sends: u64,
    /// Sends that failed.
    pub failures: u64,
    /// Backing off after repeated failures.
    pub backing_off: bool,
}

/// Everything `/status` reports, merged from the processing thread.
#[derive(Debug)]
pub struct Stats {
    /// Processing counters (latest snapshot).
    pub counters: Counters,
    /// Each source's counters, read as `/status` asks.
    pub inputs: Vec<Arc<InputCounters>>,
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
    /// Each subscriber.
    pub subscribers: Vec<SubscriberStatus>,
    /// The default model's file.
    pub model: String,
    /// Control messages refused (not allowed, no secret, bad arguments, refused commands).
    pub control_refused: u64,
    /// Frames from sources outside `frames_allow`.
    pub dropped_not_allowed: u64,
    /// Each source's own status pairs (`natnet/...`), by source, as the source last told.
    pub sources: Vec<(&'static str, Vec<(String, StatusValue)>)>,
    /// Per stream id: end-to-end latency from the source's capture time (NatNet: camera
    /// mid-exposure, through the echo's clock offset; OSC: a UTC capture time), µs.
    pub stream_latency_us: Vec<(i32, Histogram<u64>)>,
    /// The recording running: the edited stream's file, and the raw input's.
    pub recording: Option<(String, Option<String>)>,
    /// Why the last recording stopped by itself (a full disk), until the next `/record/start`.
    pub recording_error: Option<String>,
    /// The monitor page's counters (all 0 when it is off).
    pub monitor: MonitorCounters,
}

/// The monitor page's counters, for `/status` and the page itself.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MonitorCounters {
    /// Pages connected now.
    pub viewers: u64,
    /// Feed messages a slow page did not take, dropped.
    pub dropped: u64,
    /// Snapshots the processing thread did not publish because the page's side held the board.
    pub unpublished: u64,
    /// Requests refused: no or a wrong token, a foreign Origin or Host, too many pages.
    pub refused: u64,
}

impl Default for Stats {
    fn default() -> Self {
        Stats::new()
    }
}

impl Stats {
    /// An empty latency histogram, 1 µs to 60 s at 3 significant digits.
    pub fn histogram() -> Histogram<u64> {
        latency::histogram()
    }

    /// Sets what source `name` tells of itself in `/status`.
    pub fn set_source_status(&mut self, name: &'static str, pairs: Vec<(String, StatusValue)>) {
        match self.sources.iter_mut().find(|(n, _)| *n == name) {
            Some(slot) => slot.1 = pairs,
            None => self.sources.push((name, pairs)),
        }
    }

    /// Every source's counters, summed.
    pub fn input(&self) -> InputTotals {
        let mut total = InputTotals::default();
        for i in &self.inputs {
            total.add(&i.snapshot());
        }
        total
    }

    /// Empty stats.
    pub fn new() -> Stats {
        Stats {
            counters: Counters::default(),
            inputs: Vec::new(),
            send: SendCounters::default(),
            processed_us: Stats::histogram(),
            sent_us: Stats::histogram(),
            clients: 0,
            streams: 0,
            poll_hits: 0,
            poll_misses: 0,
            per_stream: Vec::new(),
            subscribers: Vec::new(),
            model: String::new(),
            control_refused: 0,
            dropped_not_allowed: 0,
            sources: Vec::new(),
            stream_latency_us: Vec::new(),
            recording: None,
            recording_error: None,
            monitor: MonitorCounters::default(),
        }
    }

    /// Records one latency in microseconds, saturating at the histogram's top.
    pub fn record(h: &mut Histogram<u64>, us: u64) {
        latency::record(h, us);
    }

    /// The counters as `(name, value)` pairs, `i` being the sources' counters summed.
    fn counter_pairs(&self, i: &InputTotals) -> Vec<(String, StatusValue)> {
        let c = &self.counters;
        [
            ("frames_in", i.frames_in),
            ("frames_out", c.frames_out),
            ("frames_dropped", c.dropped_queue_full),
            ("dropped_duplicate", c.dropped_duplicate),
            ("dropped_stale", c.dropped_stale),
            ("dropped_no_layout", i.dropped_no_layout),
            ("dropped_unmatched", c.dropped_unmatched),
            ("dropped_not_allowed", self.dropped_not_allowed),
            ("frame_errors", c.frame_errors + self.send.encode_errors),
            ("labels_in", i.labels_in),
            ("labels_refused", i.labels_refused),
            ("missing_markers", c.missing_markers),
            ("glitches", c.glitches),
            ("restarts", c.restarts),
            ("model_swaps", c.model_swaps),
            ("bad_packets", i.bad_total()),
            ("control_refused", self.control_refused),
            ("datagrams_sent", self.send.datagrams_sent),
            ("send_errors", self.send.send_errors),
            ("send_backoffs", self.send.backoffs),
            ("clients_dropped", self.send.clients_dropped),
            ("dropped_send_buffer", self.send.dropped_send_buffer),
            ("clients", self.clients),
            ("streams", self.streams),
            ("poll_hits", self.poll_hits),
            ("poll_misses", self.poll_misses),
            ("monitor_viewers", self.monitor.viewers),
            ("monitor_dropped", self.monitor.dropped),
            ("monitor_unpublished", self.monitor.unpublished),
            ("monitor_refused", self.monitor.refused),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), int(v)))
        .collect()
    }

    /// `(name, value)` pairs in the order `/status/confirm` carries them: the counters, each
    /// stream (`stream/<id>/...`), each subscriber (`subscriber/<n>/...`), the latencies.
    pub fn pairs(&self) -> Vec<(String, StatusValue)> {
        let i = self.input();
        let mut out = self.counter_pairs(&i);
        for kind in DecodeErrorKind::ALL {
            out.push((format!("bad_{}", kind.as_str()), int(i.bad[kind.index()])));
        }
        // Frames of a binary protocol that did not decode, by source (`bad_natnet`).
        for source in self.inputs.iter().filter(|s| s.bad_frames_counted()) {
            let bad = source.snapshot().bad_frames;
            out.push((format!("bad_{}", source.name), int(bad)));
        }
        out.push(("model".into(), StatusValue::Text(self.model.clone())));
        let recording = self.recording.as_ref().map_or("", |r| r.0.as_str());
        out.push(("recording".into(), StatusValue::Text(recording.into())));
        let error = self.recording_error.as_deref().unwrap_or("");
        out.push(("recording_error".into(), StatusValue::Text(error.into())));
        for st in &self.per_stream {
            stream_pairs(st, &mut out);
        }
        for (id, h) in &self.stream_latency_us {
            for (q, label) in [(0.5, "p50"), (0.99, "p99")] {
                let name = format!("stream/{id}/latency_{label}_us");
                out.push((name, int(h.value_at_quantile(q))));
            }
        }
        for (n, sub) in self.subscribers.iter().enumerate() {
            subscriber_pairs(n, sub, &mut out);
        }
        for (_, pairs) in &self.sources {
            out.extend(pairs.iter().cloned());
        }
        for (name, h) in [("processed", &self.processed_us), ("sent", &self.sent_us)] {
            for (q, label) in [(0.5, "p50"), (0.99, "p99"), (0.999, "p999")] {
                out.push((format!("{name}_{label}_us"), int(h.value_at_quantile(q))));
            }
            out.push((format!("{name}_max_us"), int(h.max())));
        }
        out
    }

    /// Logs a one-line summary.
    pub fn log(&self) {
        let (c, i) = (&self.counters, self.input());
        tracing::info!(
            target: "emoshift",
            frames_in = i.frames_in,
            frames_out = c.frames_out,
            dropped = c.dropped_queue_full
                + c.dropped_stale
                + c.dropped_duplicate
                + i.dropped_no_layout
                + c.dropped_unmatched
                + self.dropped_not_allowed,
            labels_refused = i.labels_refused,
            control_refused = self.control_refused,
            bad_packets = i.bad_total(),
            missing_markers = c.missing_markers,
            clients = self.clients,
            streams = self.streams,
            processed_p99_us = self.processed_us.value_at_quantile(0.99),
            sent_p99_us = self.sent_us.value_at_quantile(0.99),
            "status"
        );
        for st in &self.per_stream {
            tracing::info!(
                target: "emoshift",
                id = st.id,
                name = %st.name,
                source = %st.key.source,
                layout = st.key.layout_id,
                frames = st.frames,
                dropped_duplicate = st.duplicates,
                dropped_stale = st.stale,
                "stream"
            );
        }
    }
}

fn int(v: u64) -> StatusValue {
    StatusValue::Int(i64::try_from(v).unwrap_or(i64::MAX))
}

fn stream_pairs(st: &StreamStatus, out: &mut Vec<(String, StatusValue)>) {
    let at = format!("stream/{}", st.id);
    let text = |s: String| StatusValue::Text(s);
    out.push((format!("{at}/name"), text(st.name.clone())));
    out.push((
        format!("{at}/source"),
        text(format!("{}/{}", st.key.source, st.key.layout_id)),
    ));
    out.push((format!("{at}/emotion"), text(st.target.clone())));
    out.push((format!("{at}/amount"), text(format!("{:.3}", st.amount))));
    for (what, v) in [
        ("model_markers", st.model_markers as u64),
        ("unmatched_markers", st.unmatched_markers as u64),
        ("frames", st.frames),
        ("dropped_duplicate", st.duplicates),
        ("dropped_stale", st.stale),
    ] {
        out.push((format!("{at}/{what}"), int(v)));
    }
}

fn subscriber_pairs(n: usize, sub: &SubscriberStatus, out: &mut Vec<(String, StatusValue)>) {
    let at = format!("subscriber/{n}");
    let text = |s: &str| StatusValue::Text(s.to_string());
    out.push((format!("{at}/address"), text(&sub.addr.to_string())));
    out.push((format!("{at}/profile"), text(sub.profile.as_str())));
    out.push((
        format!("{at}/performer"),
        text(sub.performer.as_deref().unwrap_or("")),
    ));
    let lease = sub
        .lease_ms
        .map_or(-1, |ms| i64::try_from(ms).unwrap_or(i64::MAX));
    out.push((format!("{at}/lease_ms"), StatusValue::Int(lease)));
    out.push((format!("{at}/sends"), int(sub.sends)));
    out.push((format!("{at}/failures"), int(sub.failures)));
    out.push((format!("{at}/backing_off"), int(u64::from(sub.backing_off))));
}

/// The `/status` pairs of the output `name`, into `stats`.
pub fn status_into(
    stats: &Arc<std::sync::Mutex<Stats>>,
    name: &'static str,
) -> impl FnMut(Vec<(String, protocol::StatusValue)>) + Send + 'static {
    let stats = Arc::clone(stats);
    move |pairs| {
        if let Ok(mut s) = stats.lock() {
            s.set_source_status(name, pairs);
        }
    }
}

/// Logs the status every `every` until shutdown.
pub async fn log_stats(
    stats: Arc<std::sync::Mutex<Stats>>,
    every: std::time::Duration,
    shutdown: tokio_util::sync::CancellationToken,
) {
    let mut tick = tokio::time::interval(every);
    tick.tick().await;
    loop {
        tokio::select! {
            () = shutdown.cancelled() => break,
            _ = tick.tick() => if let Ok(s) = stats.lock() { s.log() },
        }
    }
}

/// What `/status` says of the default model: its file, or `none` (frames pass through).
pub(crate) fn model_name(path: Option<&std::path::Path>) -> String {
    path.map_or_else(|| "none".to_string(), |p| p.display().to_string())
}

#[cfg(test)]
mod tests;
