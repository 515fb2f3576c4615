//! The processing thread: OSC frames read off the frame socket on this thread, and the other
//! sources' frames off the [`super::queue`], through the [`Pipeline`] and straight out to every
//! sink ([`Outputs`]: the OSC subscribers first); control commands between frames; counters
//! merged into the shared [`Stats`] between bursts. While nothing is waiting it sleeps in one
//! [`Inbox`] wait on the socket and its doorbell, or polls around a steady source's next
//! expected frame ([`ArrivalClock`]).
//!
//! One frame from an OSC source: [`Inbox::recv`] → [`OscIntake::datagram`] (allow-list, demux)
//! → [`Pipeline::handle_frame`] → the [`Tap`] (latencies) → [`Outputs::handle_frame`] (each
//! sink sends or stores it), all before the next datagram is read.

mod inbox;
mod requests;
mod wait;

use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crossbeam_channel::Receiver;
use engine::pipeline::{Pipeline, QUIET_SWEEPS, SWEEP_SECONDS};
use engine::{Needs, Processed, Sink, SourceFrame};
use hdrhistogram::Histogram;
use tokio_util::sync::CancellationToken;

use super::arrival::{ArrivalClock, SpinWindow, Wait};
use super::command::Request;
use super::latency::{self, StreamLatency};
use super::queue::{QueueEnds, QueuedFrame};
use super::sinks::Outputs;
use super::sources::osc::OscIntake;
use super::sources::Arrival;
use super::stats::{Stats, SubscriberStatus};
pub(crate) use inbox::Inbox;
use wait::Next;

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
/// Datagrams read off the frame socket, or frames off the queue, before the thread looks at
/// its other inputs (a flood on one delays the others by this many frames at most).
const BURST: usize = 64;

/// What the processing thread takes frames and commands from.
pub(crate) struct Inputs {
    /// The OSC frame socket and the doorbell.
    pub(crate) inbox: Inbox,
    /// What the frame socket's datagrams become.
    pub(crate) osc: OscIntake,
    /// The other sources' frames.
    pub(crate) queue: QueueEnds,
    /// Control commands.
    pub(crate) commands: Receiver<Request>,
    /// Stops reading the socket; the queue is drained until its sources have stopped.
    pub(crate) shutdown: CancellationToken,
}

/// What the processing thread shares with the rest of the service.
pub(crate) struct Shared {
    /// Counters for `/status` and the log, merged in between bursts.
    pub(crate) stats: Arc<Mutex<Stats>>,
    /// Frames the sources dropped because the queue was full.
    pub(crate) queue_dropped: Arc<AtomicU64>,
    /// Frames the OSC source dropped because their sender is not allowed.
    pub(crate) not_allowed: Arc<AtomicU64>,
}

impl Shared {
    /// Counters at zero beside `stats`.
    pub(crate) fn new(stats: Arc<Mutex<Stats>>) -> Shared {
        Shared {
            stats,
            queue_dropped: Arc::default(),
            not_allowed: Arc::default(),
        }
    }
}

/// The processing thread's state.
pub(crate) struct Processing {
    pipeline: Pipeline,
    outputs: Outputs,
    arrival: ArrivalClock,
    poll_hits: u64,
    poll_misses: u64,
    inbox: Inbox,
    /// The OSC intake and its datagram buffer (taken out while a datagram is processed).
    osc: Option<(OscIntake, Vec<u8>)>,
    queue: QueueEnds,
    cmd_rx: Receiver<Request>,
    shutdown: CancellationToken,
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
        inputs: Inputs,
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
            inbox: inputs.inbox,
            osc: Some((inputs.osc, vec![0u8; protocol::MAX_UDP_PAYLOAD + 1])),
            queue: inputs.queue,
            cmd_rx: inputs.commands,
            shutdown: inputs.shutdown,
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

    /// Runs until shutdown and every other source closed the queue, then closes the
    /// recording.
    pub(crate) fn run(mut self) {
        while !self.shutdown.is_cancelled() {
            let (timeout, idle) = match self.plan_wait() {
                Next::WaitIdle(t) => (t, true),
                Next::WaitBeat(t) => (t, false),
                Next::PlanAgain => continue,
            };
            // A ring the plan's polling took still left its frame or command waiting.
            let waiting = !self.queue.frames.is_empty() || !self.cmd_rx.is_empty();
            let woke = self
                .inbox
                .wait(if waiting { Duration::ZERO } else { timeout });
            if !self.take_inputs() && !woke && idle {
                self.tidy();
            }
        }
        self.inbox.close_socket();
        // The other sources stop on the same token; what they queued before is processed.
        while let Ok(frame) = self.queue.frames.recv() {
            self.on_queued(frame);
        }
        self.merge_stats();
        // Shutdown waits for every file to be complete.
        std::mem::take(&mut self.outputs.recorder).finish();
    }

    /// What is waiting: datagrams on the socket, queued frames, then commands, at most a
    /// [`BURST`] of each kind of frame; whether there was anything.
    fn take_inputs(&mut self) -> bool {
        let mut took = self.read_socket();
        for _ in 0..BURST {
            let Ok(frame) = self.queue.frames.try_recv() else {
                break;
            };
            self.on_queued(frame);
            took = true;
        }
        while let Ok(cmd) = self.cmd_rx.try_recv() {
            self.command(cmd);
            took = true;
        }
        took
    }

    /// Up to a [`BURST`] of datagrams off the frame socket, each through the engine before
    /// the next is read.
    fn read_socket(&mut self) -> bool {
        let Some((mut osc, mut buf)) = self.osc.take() else {
            return false;
        };
        let mut took = false;
        for _ in 0..BURST {
            let Some((len, peer)) = self.inbox.recv(&mut buf) else {
                break;
            };
            took = true;
            let received = Instant::now();
            osc.datagram(peer, &buf[..len], received, &mut |frame, arrival| {
                self.on_frame(frame, arrival);
            });
        }
        self.osc = Some((osc, buf));
        took
    }

    fn on_queued(&mut self, frame: QueuedFrame) {
        self.on_frame(&frame.source(), &frame.arrival);
        let _ = self.queue.free.try_send(frame.into_buffer());
    }

    fn on_frame(&mut self, frame: &SourceFrame<'_>, arrival: &Arrival) {
        let received = arrival.received;
        self.process(frame, arrival);
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

    /// One frame through the engine to every sink; its source hears why if it was refused.
    fn process(&mut self, frame: &SourceFrame<'_>, arrival: &Arrival) {
        let mut tap = Tap {
            outputs: &mut self.outputs,
            received: arrival.received,
            captured: arrival.captured,
            processed_us: &mut self.processed_us,
            latency: &mut self.latency,
        };
        self.pipeline.handle_frame(frame, &mut tap);
        if let Some(refusal) = self.pipeline.poll_refusal() {
            if let Some(answer) = &arrival.answer {
                answer.tell(refusal.key.source, &refusal.why);
            }
        }
    }

    /// Between frames: streams gone quiet, subscriptions whose lease ended, recordings done
    /// closing.
    fn housekeeping(&mut self) {
        self.outputs.recorder.tidy();
        if self.last_sweep.elapsed() >= Duration::from_secs(SWEEP_SECONDS) {
            self.last_sweep = Instant::now();
            if let Some((osc, _)) = &mut self.osc {
                osc.forget_quiet_sources();
            }
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
