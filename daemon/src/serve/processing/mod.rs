//! The processing thread: the sources' frames off the [`super::queue`] through the [`Pipeline`] and
//! straight out to every sink ([`Outputs`]: the OSC subscribers first); control commands
//! between frames; counters merged into the shared [`Stats`] between bursts. While its queue
//! is empty it parks, or polls around a steady source's next expected frame
//! ([`ArrivalClock`]).

mod requests;

use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crossbeam_channel::Receiver;
use engine::pipeline::{Pipeline, QUIET_SWEEPS, SWEEP_SECONDS};
use engine::{Needs, Processed, Sink};
use hdrhistogram::Histogram;

use super::arrival::{ArrivalClock, SpinWindow, Wait};
use super::command::Request;
use super::latency::{self, StreamLatency};
use super::queue::{QueueEnds, QueuedFrame};
use super::sinks::Outputs;
use super::stats::{Stats, SubscriberStatus};

/// The processing thread merges its counters and histograms into the shared [`Stats`] (a
/// lock, a histogram add and reset: tens of µs) only between bursts, at most this often: with
/// a steady source, while it waits for the next tick with [`QUIET`] to spare (right after a
/// frame, the next performer's frame of the same tick may be on its way); otherwise when its
/// queue is empty; and after 50 ms idle or a command.
const MERGE_EVERY: Duration = Duration::from_millis(100);
/// ... and at least this often under sustained load, when the queue is never empty.
const MERGE_AT_LEAST: Duration = Duration::from_secs(1);
/// Time to spare before the next tick for a merge.
const QUIET: Duration = Duration::from_millis(2);
/// The processing thread parks at most this long between two looks at its counters.
const IDLE: Duration = Duration::from_millis(50);

/// What the processing thread shares with the rest of the service.
pub(crate) struct Shared {
    /// Counters for `/status` and the log, merged in between bursts.
    pub(crate) stats: Arc<Mutex<Stats>>,
    /// Frames the sources dropped because the queue was full.
    pub(crate) queue_dropped: Arc<AtomicU64>,
    /// Frames the OSC source dropped because their sender is not allowed.
    pub(crate) not_allowed: Arc<AtomicU64>,
}

/// What the processing thread does while its queue is empty.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Next {
    /// Wait up to this long for a frame or a command; a timeout means nothing came for a
    /// while, a good moment to tidy.
    WaitIdle(Duration),
    /// Wait up to this long: a planned wake-up before the next beat, nothing to tidy.
    WaitBeat(Duration),
    /// The counters were merged in the gap before the next tick; plan again.
    PlanAgain,
}

/// The processing thread's state.
pub(crate) struct Processing {
    pipeline: Pipeline,
    outputs: Outputs,
    arrival: ArrivalClock,
    poll_hits: u64,
    poll_misses: u64,
    queue: QueueEnds,
    cmd_rx: Receiver<Request>,
    stats: Arc<Mutex<Stats>>,
    queue_dropped: Arc<AtomicU64>,
    not_allowed: Arc<AtomicU64>,
    /// When the counters were last merged into the shared stats.
    last_merge: Instant,
    /// When quiet streams were last swept ([`Pipeline::forget_quiet_streams`]).
    last_sweep: Instant,
    /// Ids of the streams the log has announced (the streams now, at most 64).
    announced: Vec<i32>,
    processed_us: Histogram<u64>,
    /// Per stream id, capture → processed (see [`super::latency`]).
    latency: StreamLatency,
}

impl Processing {
    /// A processing thread's state; [`Processing::run`] runs it.
    pub(crate) fn new(
        (pipeline, outputs): (Pipeline, Outputs),
        poll_window: Duration,
        (queue, cmd_rx): (QueueEnds, Receiver<Request>),
        shared: Shared,
    ) -> Processing {
        Processing {
            pipeline,
            outputs,
            arrival: ArrivalClock::new(SpinWindow {
                lead: poll_window,
                grace: poll_window / 2,
            }),
            poll_hits: 0,
            poll_misses: 0,
            queue,
            cmd_rx,
            stats: shared.stats,
            queue_dropped: shared.queue_dropped,
            not_allowed: shared.not_allowed,
            last_merge: Instant::now(),
            last_sweep: Instant::now(),
            announced: Vec::new(),
            processed_us: latency::histogram(),
            latency: StreamLatency::default(),
        }
    }

    /// Runs until every source closed the queue, then closes the recording.
    pub(crate) fn run(mut self) {
        loop {
            let (timeout, idle) = match self.plan_wait() {
                Next::WaitIdle(t) => (t, true),
                Next::WaitBeat(t) => (t, false),
                Next::PlanAgain => continue,
            };
            crossbeam_channel::select! {
                recv(self.queue.frames) -> msg => match msg {
                    Ok(frame) => self.on_frame(frame),
                    Err(_) => break,
                },
                recv(self.cmd_rx) -> cmd => if let Ok(cmd) = cmd {
                    self.command(cmd);
                },
                default(timeout) => if idle { self.tidy() },
            }
        }
        self.merge_stats();
        // Shutdown waits for every file to be complete.
        std::mem::take(&mut self.outputs.recorder).finish();
    }

    /// How long to wait for the next frame or command (polling first when a beat is due).
    fn plan_wait(&mut self) -> Next {
        if !self.queue.frames.is_empty() {
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

    fn on_frame(&mut self, frame: QueuedFrame) {
        let received = frame.arrival.received;
        self.process(frame);
        // Only frames are queued (labels, bad packets and noise stay with their source), so
        // each sets the beat.
        self.arrival.frame_arrived(received);
        let since = self.last_merge.elapsed();
        // No tick to wait for (no beat, or one too fast or missed): merge whenever the queue
        // runs empty, as there is no better gap coming.
        let unsteady = self.arrival.plan(Instant::now()) == Wait::Park;
        if since >= MERGE_AT_LEAST
            || (unsteady && since >= MERGE_EVERY && self.queue.frames.is_empty())
        {
            self.tidy();
        }
    }

    /// Counters into the shared stats, then housekeeping.
    fn tidy(&mut self) {
        self.merge_stats();
        self.housekeeping();
        self.last_merge = Instant::now();
    }

    /// Polls the queues until something comes or `until`; `true` when a frame came. No
    /// `spin_loop` hint: a hypervisor may take a run of PAUSE instructions as lock contention
    /// and deschedule the CPU.
    fn poll_until(&self, until: Instant) -> bool {
        loop {
            if !self.queue.frames.is_empty() {
                return true;
            }
            if !self.cmd_rx.is_empty() || Instant::now() >= until {
                return false;
            }
        }
    }

    /// One frame through the engine to every sink; its source hears why if it was refused.
    fn process(&mut self, frame: QueuedFrame) {
        let mut tap = Tap {
            outputs: &mut self.outputs,
            received: frame.arrival.received,
            captured: frame.arrival.captured,
            processed_us: &mut self.processed_us,
            latency: &mut self.latency,
        };
        self.pipeline.handle_frame(&frame.source(), &mut tap);
        if let Some(refusal) = self.pipeline.poll_refusal() {
            if let Some(answer) = &frame.arrival.answer {
                answer.tell(refusal.key.source, &refusal.why);
            }
        }
        let _ = self.queue.free.try_send(frame.into_buffer());
    }

    /// Between frames: streams gone quiet, subscriptions whose lease ended, recordings done
    /// closing.
    fn housekeeping(&mut self) {
        self.outputs.recorder.tidy();
        if self.last_sweep.elapsed() >= Duration::from_secs(SWEEP_SECONDS) {
            self.last_sweep = Instant::now();
            let gone = self.pipeline.forget_quiet_streams();
            if !gone.is_empty() {
                self.outputs.handle_gone(&gone);
                let mut list: Vec<String> = gone
                    .iter()
                    .take(8)
                    .map(|k| format!("{}/{}", k.source, k.layout_id))
                    .collect();
                if gone.len() > 8 {
                    list.push(format!("and {} more", gone.len() - 8));
                }
                tracing::info!(
                    target: "emoshift",
                    streams = %list.join(", "),
                    count = gone.len(),
                    silent_s = QUIET_SWEEPS * SWEEP_SECONDS,
                    "forgot streams gone silent"
                );
            }
        }
        self.outputs.osc.expire(Instant::now());
    }

    fn merge_stats(&mut self) {
        let Ok(mut s) = self.stats.lock() else { return };
        s.counters = self.pipeline.counters.clone();
        s.counters.dropped_queue_full = self.queue_dropped.load(Ordering::Relaxed);
        s.dropped_not_allowed = self.not_allowed.load(Ordering::Relaxed);
        let now = Instant::now();
        let osc = &mut self.outputs.osc;
        s.subscribers = osc
            .subscribers()
            .map(|c| SubscriberStatus {
                addr: c.addr,
                profile: c.wants,
                performer: c.performer.clone(),
                lease_ms: c.lease_left(now).map(|d| d.as_millis() as u64),
                sends: c.sends,
                failures: c.failures_total,
                backing_off: c.is_backing_off(),
            })
            .collect();
        s.streams = self.pipeline.stream_count() as u64;
        s.per_stream = self.pipeline.stream_status();
        announce_streams(&mut self.announced, &s.per_stream);
        s.send = osc.counters.clone();
        s.clients = osc.len() as u64;
        // Same bounds on both sides, so adding never fails.
        let _ = s.sent_us.add(&osc.sent_us);
        osc.sent_us.reset();
        (s.poll_hits, s.poll_misses) = (self.poll_hits, self.poll_misses);
        s.recording_error = self.outputs.recorder.error().map(str::to_string);
        s.recording = self.outputs.recorder.paths().map(|(path, raw)| {
            let show = |p: &Path| p.display().to_string();
            (show(path), raw.map(show))
        });
        let _ = s.processed_us.add(&self.processed_us);
        self.processed_us.reset();
        self.latency.merge_into(&mut s.stream_latency_us);
    }
}

/// What the engine's sink is for one frame: the outputs, with the frame's latencies recorded
/// as it reaches them.
struct Tap<'a> {
    outputs: &'a mut Outputs,
    received: Instant,
    captured: Option<Instant>,
    processed_us: &'a mut Histogram<u64>,
    latency: &'a mut StreamLatency,
}

impl Sink for Tap<'_> {
    fn needs(&self) -> Needs {
        self.outputs.needs()
    }

    fn handle_frame(&mut self, frame: &Processed<'_>) {
        let processed = Instant::now();
        let us = processed.duration_since(self.received).as_micros() as u64;
        latency::record(self.processed_us, us);
        self.latency
            .record(frame.identity().id, self.captured, processed);
        self.outputs.handle_frame(frame);
    }
}

/// Logs each stream once as it appears, with how many of its model's markers its source names:
/// the others are filled from the model, which only `/status` said.
fn announce_streams(announced: &mut Vec<i32>, streams: &[engine::StreamStatus]) {
    for st in streams {
        if announced.contains(&st.id) {
            continue;
        }
        announced.push(st.id);
        let named = st.model_markers.saturating_sub(st.unmatched_markers);
        if st.unmatched_markers == 0 {
            tracing::info!(target: "emoshift", stream = %st.name, markers = st.model_markers, "stream started");
        } else {
            tracing::warn!(
                target: "emoshift",
                stream = %st.name,
                "stream started: its source names {named} of the model's {} markers; the other {} are filled from the model",
                st.model_markers,
                st.unmatched_markers
            );
        }
    }
    announced.retain(|id| streams.iter().any(|st| st.id == *id));
}

#[cfg(test)]
mod tests;
