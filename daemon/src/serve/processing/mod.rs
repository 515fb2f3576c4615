//! The processing thread: frames from the receive task's queue through the [`Pipeline`] and
//! straight out to the subscribers ([`Fanout`]); control commands between frames; the
//! recording; counters merged into the shared [`Stats`] between bursts. While its queue is
//! empty it parks, or polls around a steady source's next expected frame ([`ArrivalClock`]).

mod requests;

use std::collections::HashMap;
use std::net::SocketAddr;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crossbeam_channel::{Receiver, Sender};

use super::arrival::{ArrivalClock, SpinWindow, Wait};
use super::command::Request;
use super::monitor::Feed;
use super::record::{finish_recording, Recording};
use super::sender::Fanout;
use super::stats::{Stats, SubscriberStatus};
use crate::engine::pipeline::{Emitted, Pipeline, Refusal as Refused, QUIET_SWEEPS, SWEEP_SECONDS};

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
/// A source hears why its datagram was refused at most this often.
const TELL_EVERY: Duration = Duration::from_secs(1);
/// The processing thread parks at most this long between two looks at its counters.
const IDLE: Duration = Duration::from_millis(50);
/// One received datagram.
#[derive(Debug)]
pub(crate) struct InFrame {
    pub(crate) peer: SocketAddr,
    pub(crate) bytes: Vec<u8>,
    pub(crate) received: Instant,
    /// A NAT_FRAMEOFDATA and the NatNet session that decodes it; `None` for OSC.
    pub(crate) natnet: Option<Arc<crate::serve::natnet::Session>>,
}

/// The processing thread's ends of the channels.
pub(crate) struct Channels {
    /// Received frames (bounded; the receive task drops the oldest when full).
    pub(crate) frames: Receiver<InFrame>,
    /// Datagram buffers handed back to the receive task.
    pub(crate) free: Sender<Vec<u8>>,
    /// Control commands, applied between frames.
    pub(crate) commands: Receiver<Request>,
}

/// What the processing thread shares with the rest of the service.
pub(crate) struct Shared {
    /// Counters for `/status` and the log, merged in between bursts.
    pub(crate) stats: Arc<Mutex<Stats>>,
    /// Frames the receive task dropped because the queue was full.
    pub(crate) queue_dropped: Arc<AtomicU64>,
    /// Frames the receive task dropped because their source is not allowed.
    pub(crate) not_allowed: Arc<AtomicU64>,
    /// The frame socket, to tell a source why its datagram was refused (`None` in tests).
    pub(crate) replies: Option<std::net::UdpSocket>,
    /// The monitor page's feed, when the page is served.
    pub(crate) monitor: Option<Feed>,
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
    fanout: Fanout,
    arrival: ArrivalClock,
    poll_hits: u64,
    poll_misses: u64,
    frame_rx: Receiver<InFrame>,
    free_tx: Sender<Vec<u8>>,
    cmd_rx: Receiver<Request>,
    stats: Arc<Mutex<Stats>>,
    queue_dropped: Arc<AtomicU64>,
    not_allowed: Arc<AtomicU64>,
    /// The frame socket, for refusals a source should hear, and when each source last heard one.
    replies: Option<std::net::UdpSocket>,
    told: HashMap<SocketAddr, Instant>,
    /// When a refusal was last logged, and the refusals not logged since (many sources at
    /// once, spoofed or not, log one line a second).
    refusals_logged: (Option<Instant>, u64),
    recording: Option<Recording>,
    /// Recordings being closed on their own threads.
    closing: Vec<std::thread::JoinHandle<()>>,
    /// When the counters were last merged into the shared stats.
    last_merge: Instant,
    /// When quiet sources were last swept ([`Pipeline::forget_quiet_sources`]).
    last_sweep: Instant,
    /// Ids of the streams the log has announced (the streams now, at most 64).
    announced: Vec<i32>,
    processed_us: hdrhistogram::Histogram<u64>,
    /// Per stream id, capture → processed (see [`super::latency`]).
    latency: super::latency::StreamLatency,
    monitor: Option<Feed>,
}

impl Processing {
    /// A processing thread's state; [`Processing::run`] runs it.
    pub(crate) fn new(
        pipeline: Pipeline,
        fanout: Fanout,
        poll_window: Duration,
        channels: Channels,
        shared: Shared,
    ) -> Processing {
        let mut processing = Processing {
            pipeline,
            fanout,
            arrival: ArrivalClock::new(SpinWindow {
                lead: poll_window,
                grace: poll_window / 2,
            }),
            poll_hits: 0,
            poll_misses: 0,
            frame_rx: channels.frames,
            free_tx: channels.free,
            cmd_rx: channels.commands,
            stats: shared.stats,
            queue_dropped: shared.queue_dropped,
            not_allowed: shared.not_allowed,
            replies: shared.replies,
            told: HashMap::new(),
            refusals_logged: (None, 0),
            recording: None,
            closing: Vec::new(),
            last_merge: Instant::now(),
            last_sweep: Instant::now(),
            announced: Vec::new(),
            processed_us: Stats::histogram(),
            latency: super::latency::StreamLatency::default(),
            monitor: shared.monitor,
        };
        processing.pipeline.set_wanted(processing.fanout.wanted());
        processing
    }

    /// Runs until the receive task closes the queue, then closes the recording.
    pub(crate) fn run(mut self) {
        loop {
            let (timeout, idle) = match self.plan_wait() {
                Next::WaitIdle(t) => (t, true),
                Next::WaitBeat(t) => (t, false),
                Next::PlanAgain => continue,
            };
            crossbeam_channel::select! {
                recv(self.frame_rx) -> msg => match msg {
                    Ok(frame) => self.on_frame(frame),
                    Err(_) => break,
                },
                recv(self.cmd_rx) -> cmd => if let Ok(cmd) = cmd {
                    self.command(cmd);
                    // So that a `/status` right after a command sees its effect.
                    self.merge_stats();
                },
                default(timeout) => if idle { self.tidy() },
            }
        }
        self.merge_stats();
        if let Some(rec) = self.recording.take() {
            finish_recording(rec);
        }
        // Shutdown waits for every file to be complete.
        for closing in self.closing.drain(..) {
            let _ = closing.join();
        }
    }

    /// How long to wait for the next frame or command (polling first when a beat is due).
    fn plan_wait(&mut self) -> Next {
        if !self.frame_rx.is_empty() {
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

    fn on_frame(&mut self, frame: InFrame) {
        let received = frame.received;
        let frames_before = self.pipeline.counters.frames_in;
        self.process(frame);
        // Only frames set the beat: labels, bad packets and noise do not.
        if self.pipeline.counters.frames_in > frames_before {
            self.arrival.frame_arrived(received);
        }
        let since = self.last_merge.elapsed();
        // No tick to wait for (no beat, or one too fast or missed): merge whenever the queue
        // runs empty, as there is no better gap coming.
        let unsteady = self.arrival.plan(Instant::now()) == Wait::Park;
        if since >= MERGE_AT_LEAST || (unsteady && since >= MERGE_EVERY && self.frame_rx.is_empty())
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
            if !self.frame_rx.is_empty() {
                return true;
            }
            if !self.cmd_rx.is_empty() || Instant::now() >= until {
                return false;
            }
        }
    }

    fn process(&mut self, frame: InFrame) {
        let Processing {
            pipeline,
            fanout,
            recording,
            processed_us,
            latency,
            ..
        } = self;
        let received = frame.received;
        let natnet = frame.natnet.as_deref();
        let mut clients_changed = false;
        let mut last = None;
        let mut emit = |e: &Emitted<'_>| {
            last = Some(e.key);
            let processed = Instant::now();
            Stats::record(
                processed_us,
                processed.duration_since(received).as_micros() as u64,
            );
            latency.record(e, natnet, processed);
            // Send before recording: the file write is not on the subscribers' path.
            clients_changed |= fanout.send(e, processed);
            if let Some(rec) = recording.as_mut() {
                rec.push(e);
            }
        };
        match natnet {
            Some(s) => pipeline.handle_natnet(s.server, &frame.bytes, &s.layout, &mut emit),
            None => pipeline.handle_datagram(frame.peer, &frame.bytes, &mut emit),
        }
        if clients_changed {
            self.pipeline.set_wanted(self.fanout.wanted());
        }
        // After the sends: the page's copy is never on the subscribers' path.
        if let (Some(feed), Some(key)) = (self.monitor.as_mut(), last) {
            feed.after_frame(&self.pipeline, &key);
        }
        if let Some(refusal) = self.pipeline.take_refusal() {
            self.tell_source(&refusal);
        }
        let _ = self.free_tx.try_send(frame.bytes);
    }

    /// Sends `/emoshift/error` to a source whose datagram was refused, at most once a second
    /// per source (a spoofed source cannot turn the daemon into a reflector).
    fn tell_source(&mut self, refusal: &Refused) {
        let now = Instant::now();
        if self
            .told
            .get(&refusal.to)
            .is_some_and(|t| now.duration_since(*t) < TELL_EVERY)
        {
            return;
        }
        if self.told.len() >= 256 {
            self.told.retain(|_, t| now.duration_since(*t) < TELL_EVERY);
        }
        self.told.insert(refusal.to, now);
        let (last, unlogged) = &mut self.refusals_logged;
        if last.is_none_or(|t| now.duration_since(t) >= TELL_EVERY) {
            if *unlogged > 0 {
                tracing::warn!(target: "emoshift", source = %refusal.to, why = %refusal.why, others = *unlogged, "datagram refused (and others not logged since the last)");
            } else {
                tracing::warn!(target: "emoshift", source = %refusal.to, why = %refusal.why, "datagram refused");
            }
            (*last, *unlogged) = (Some(now), 0);
        } else {
            *unlogged += 1;
        }
        let Some(socket) = &self.replies else { return };
        let mut out = Vec::with_capacity(256);
        protocol::encode_error_into(protocol::address::LABELS, &refusal.why, &mut out);
        let _ = socket.send_to(&out, refusal.to);
    }

    /// Between frames: subscriptions whose lease ended; recordings done closing.
    fn housekeeping(&mut self) {
        self.closing.retain(|h| !h.is_finished());
        if self.last_sweep.elapsed() >= Duration::from_secs(SWEEP_SECONDS) {
            self.last_sweep = Instant::now();
            let gone = self.pipeline.forget_quiet_sources();
            if !gone.is_empty() {
                let mut list: Vec<String> = gone.iter().take(8).map(ToString::to_string).collect();
                if gone.len() > 8 {
                    list.push(format!("and {} more", gone.len() - 8));
                }
                tracing::info!(
                    target: "emoshift",
                    sources = %list.join(", "),
                    "forgot {} silent for {} s or more",
                    crate::commands::count(gone.len(), "source"),
                    QUIET_SWEEPS * SWEEP_SECONDS
                );
            }
        }
        if self.fanout.expire(Instant::now()) {
            self.pipeline.set_wanted(self.fanout.wanted());
        }
    }

    fn merge_stats(&mut self) {
        let Ok(mut s) = self.stats.lock() else { return };
        s.counters = self.pipeline.counters.clone();
        s.counters.dropped_queue_full = self.queue_dropped.load(Ordering::Relaxed);
        s.dropped_not_allowed = self.not_allowed.load(Ordering::Relaxed);
        let now = Instant::now();
        s.subscribers = self
            .fanout
            .subscribers()
            .map(|c| SubscriberStatus {
                addr: c.addr,
                profile: c.profile,
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
        s.send = self.fanout.counters.clone();
        (s.poll_hits, s.poll_misses) = (self.poll_hits, self.poll_misses);
        s.clients = self.fanout.len() as u64;
        s.recording = self.recording.as_ref().map(|r| {
            let (path, raw) = r.paths();
            let show = |p: &Path| p.display().to_string();
            (show(path), raw.map(show))
        });
        // Same bounds on both sides, so adding never fails.
        let _ = s.processed_us.add(&self.processed_us);
        self.processed_us.reset();
        let _ = s.sent_us.add(&self.fanout.sent_us);
        self.fanout.sent_us.reset();
        self.latency.merge_into(&mut s.stream_latency_us);
    }
}

/// Logs each stream once as it appears, with how many of its model's markers its source names:
/// the others are filled from the model, which only `/status` said.
fn announce_streams(announced: &mut Vec<i32>, streams: &[crate::engine::StreamStatus]) {
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
mod tests {
    use super::*;
    use crate::engine::{StreamKey, StreamStatus};

    fn status(id: i32, unmatched: usize) -> StreamStatus {
        StreamStatus {
            key: StreamKey {
                source: "127.0.0.1:9000".parse().expect("addr"),
                layout_id: id,
            },
            id,
            name: format!("s{id}"),
            performer: None,
            model_markers: 109,
            unmatched_markers: unmatched,
            target: String::new(),
            amount: 0.0,
            frames: 1,
            duplicates: 0,
            stale: 0,
        }
    }

    /// Each stream is announced once while it lives, and again if it comes back after going.
    #[test]
    fn streams_are_announced_once_while_they_live() {
        let mut announced = Vec::new();
        announce_streams(&mut announced, &[status(0, 0), status(1, 69)]);
        assert_eq!(announced, [0, 1]);
        announce_streams(&mut announced, &[status(0, 0), status(1, 69)]);
        assert_eq!(announced, [0, 1]);
        announce_streams(&mut announced, &[status(1, 69)]);
        assert_eq!(announced, [1], "a stream gone is forgotten");
        announce_streams(&mut announced, &[status(1, 69), status(0, 0)]);
        assert_eq!(announced, [1, 0]);
    }
}
