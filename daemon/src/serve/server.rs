//! The only module that awaits. Tasks:
//!
//! - **receive**: frame socket → pooled buffer → bounded crossbeam channel; when full the
//!   oldest frame is dropped and counted (latest frame wins);
//! - **processing** (one blocking thread): [`Pipeline`] per frame, then the encoded bytes
//!   straight to every subscriber ([`Fanout`]), control commands (edits, subscriptions,
//!   models, recordings) between frames, recording;
//! - **control**: decodes control messages and answers them;
//! - **stats**: logs the counters every few seconds; **SIGHUP** reloads the model.
//!
//! Shutdown: the token stops receive and control; the processing thread drains the queue,
//! sends what it processes and closes the recording.

use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use crossbeam_channel::{Receiver, Sender};
use ica_core::model::IcaModel;
use tokio::net::UdpSocket;
use tokio::sync::oneshot;
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;

use super::arrival::{ArrivalClock, SpinWindow, Wait};
use super::control::{self, Cmd, ControlCtx};
use super::pipeline::{Emitted, Pipeline, PipelineConfig};
use super::record::Recording;
use super::sender::Fanout;
use super::stats::Stats;
use super::streams::Performer;
use super::Config;

/// The processing thread merges its counters and histograms into the shared [`Stats`] (a
/// lock, a histogram add and reset: tens of µs) only between bursts: when its queue is empty
/// and this long has passed since the last merge, after 50 ms idle, or after a command.
const MERGE_EVERY: Duration = Duration::from_millis(100);
/// ... and at least this often under sustained load, when the queue is never empty.
const MERGE_AT_LEAST: Duration = Duration::from_secs(1);
/// The processing thread parks at most this long between two looks at its counters.
const IDLE: Duration = Duration::from_millis(50);
/// Pooled buffers kept for received datagrams.
const POOL: usize = 256;

/// One received datagram.
#[derive(Debug)]
pub(crate) struct InFrame {
    peer: SocketAddr,
    bytes: Vec<u8>,
    received: Instant,
}

/// A server with its sockets bound and its models loaded; [`Bound::run`] serves.
#[derive(Debug)]
pub struct Bound {
    frames: UdpSocket,
    control: UdpSocket,
    config: Config,
    model: Arc<IcaModel>,
    performers: Vec<Performer>,
}

/// Loads a model file on a blocking thread.
///
/// # Errors
/// Unreadable or invalid file, named.
pub async fn load_model(path: std::path::PathBuf) -> Result<IcaModel> {
    tokio::task::spawn_blocking(move || crate::commands::load_model(&path))
        .await
        .context("model loader panicked")?
}

/// Binds both sockets and loads the models, so that a test learns the addresses before frames
/// flow (`127.0.0.1:0` gives free ports).
///
/// # Errors
/// A socket that cannot be bound or a model that cannot be loaded.
pub async fn bind(config: Config) -> Result<Bound> {
    let model = load_model(config.model.clone()).await?;
    bind_with(config, model).await
}

/// [`bind`] with the default model given instead of read from `config.model` (bench, tests).
///
/// # Errors
/// A socket that cannot be bound or a performer model that cannot be loaded.
pub async fn bind_with(config: Config, model: IcaModel) -> Result<Bound> {
    let model = Arc::new(model);
    let mut performers = Vec::with_capacity(config.performers.len());
    for p in &config.performers {
        let model = match &p.model {
            Some(path) => Some(Arc::new(load_model(path.clone()).await?)),
            None => None,
        };
        performers.push(Performer {
            name: p.name.clone(),
            source: p.source,
            layout: p.layout,
            model,
            target: p.emotion.clone(),
            amount: p.amount,
        });
    }
    let frames = super::net::bind_receiver(config.listen)
        .with_context(|| format!("binding the frame socket {}", config.listen))?;
    let control = UdpSocket::bind(config.control)
        .await
        .with_context(|| format!("binding the control socket {}", config.control))?;
    Ok(Bound {
        frames,
        control,
        config,
        model,
        performers,
    })
}

impl Bound {
    /// The frame socket's address.
    ///
    /// # Errors
    /// The OS cannot tell (not expected for a bound socket).
    pub fn frame_addr(&self) -> Result<SocketAddr> {
        Ok(self.frames.local_addr()?)
    }

    /// The control socket's address.
    ///
    /// # Errors
    /// The OS cannot tell.
    pub fn control_addr(&self) -> Result<SocketAddr> {
        Ok(self.control.local_addr()?)
    }

    /// Serves until `shutdown` is cancelled, then drains and returns.
    ///
    /// # Errors
    /// A task that failed or panicked.
    pub async fn run(self, shutdown: CancellationToken) -> Result<()> {
        let tracker = TaskTracker::new();
        let stats = Arc::new(Mutex::new(Stats::new()));
        let queue_dropped = Arc::new(AtomicU64::new(0));
        let (frame_tx, frame_rx) = crossbeam_channel::bounded::<InFrame>(self.config.queue);
        let (free_tx, free_rx) = crossbeam_channel::bounded::<Vec<u8>>(POOL);
        let (cmd_tx, cmd_rx) = crossbeam_channel::bounded::<Cmd>(64);

        let mut pipeline = Pipeline::new(
            self.model,
            self.performers,
            PipelineConfig {
                lowpass_s: self.config.lowpass_s,
                ..PipelineConfig::default()
            },
        );
        let fanout = Fanout::new(&self.config)?;
        pipeline.set_wanted(fanout.wanted());
        let window = self.config.poll_window;
        let processing = Processing {
            pipeline,
            fanout,
            arrival: ArrivalClock::new(SpinWindow {
                lead: window,
                grace: window / 2,
            }),
            poll_hits: 0,
            poll_misses: 0,
            frame_rx: frame_rx.clone(),
            free_tx,
            cmd_rx,
            stats: Arc::clone(&stats),
            queue_dropped: Arc::clone(&queue_dropped),
            recording: None,
            processed_us: Stats::histogram(),
        };
        let processing = tracker.spawn_blocking(move || processing.run());

        let receive = receive(
            self.frames,
            frame_tx,
            frame_rx,
            free_rx,
            Arc::clone(&queue_dropped),
            shutdown.clone(),
        );
        tracker.spawn(receive);
        let ctx = ControlCtx {
            socket: Arc::new(self.control),
            cmd_tx,
            stats: Arc::clone(&stats),
            model_path: Arc::new(Mutex::new(self.config.model.clone())),
            tracker: tracker.clone(),
        };
        tracker.spawn(control::run(ctx.clone(), shutdown.clone()));
        tracker.spawn(control::reload_on_sighup(ctx, shutdown.clone()));
        tracker.spawn(log_stats(
            stats,
            self.config.stats_interval,
            shutdown.clone(),
        ));
        tracker.close();
        let result = processing.await;
        tracker.wait().await;
        result.context("processing thread panicked")?
    }
}

/// Receive task: datagrams into the bounded queue, latest frame wins.
async fn receive(
    socket: UdpSocket,
    tx: Sender<InFrame>,
    rx: Receiver<InFrame>,
    free: Receiver<Vec<u8>>,
    dropped: Arc<AtomicU64>,
    shutdown: CancellationToken,
) {
    let mut buf = vec![0u8; protocol::MAX_UDP_PAYLOAD + 1];
    loop {
        let (len, peer) = tokio::select! {
            () = shutdown.cancelled() => break,
            r = socket.recv_from(&mut buf) => match r {
                Ok(r) => r,
                // ICMP errors and the like on a UDP socket: nothing to do but go on.
                Err(e) => {
                    tracing::trace!(error = %e, "frame socket receive error");
                    continue;
                }
            },
        };
        let mut bytes = free.try_recv().unwrap_or_default();
        bytes.clear();
        bytes.extend_from_slice(&buf[..len]);
        let mut item = InFrame {
            peer,
            bytes,
            received: Instant::now(),
        };
        loop {
            match tx.try_send(item) {
                Ok(()) => break,
                Err(crossbeam_channel::TrySendError::Full(back)) => {
                    item = back;
                    if rx.try_recv().is_ok() {
                        dropped.fetch_add(1, Ordering::Relaxed);
                    }
                }
                Err(crossbeam_channel::TrySendError::Disconnected(_)) => return,
            }
        }
    }
}

/// The processing thread's state.
struct Processing {
    pipeline: Pipeline,
    fanout: Fanout,
    arrival: ArrivalClock,
    poll_hits: u64,
    poll_misses: u64,
    frame_rx: Receiver<InFrame>,
    free_tx: Sender<Vec<u8>>,
    cmd_rx: Receiver<Cmd>,
    stats: Arc<Mutex<Stats>>,
    queue_dropped: Arc<AtomicU64>,
    recording: Option<Recording>,
    processed_us: hdrhistogram::Histogram<u64>,
}

impl Processing {
    fn run(mut self) -> Result<()> {
        let mut last_merge = Instant::now();
        loop {
            let now = Instant::now();
            // `idle`: the timeout below means nothing came for a while (not a planned wake-up
            // before the next beat), a good moment for the counters.
            let (timeout, idle) = match self.arrival.plan(now) {
                Wait::PollUntil(until) => {
                    if self.poll_until(until) {
                        self.poll_hits += 1;
                    } else {
                        self.poll_misses += 1;
                    }
                    (IDLE, true)
                }
                Wait::ParkUntil(at) => ((at - now).min(IDLE), false),
                Wait::Park => (IDLE, true),
            };
            crossbeam_channel::select! {
                recv(self.frame_rx) -> msg => match msg {
                    Ok(frame) => {
                        self.arrival.frame_arrived(frame.received);
                        self.process(frame);
                        let since = last_merge.elapsed();
                        if since >= MERGE_AT_LEAST
                            || (since >= MERGE_EVERY && self.frame_rx.is_empty())
                        {
                            self.merge_stats();
                            self.housekeeping();
                            last_merge = Instant::now();
                        }
                    }
                    Err(_) => break,
                },
                recv(self.cmd_rx) -> cmd => if let Ok(cmd) = cmd {
                    self.command(cmd);
                    // So that a `/status` right after a command sees its effect.
                    self.merge_stats();
                },
                default(timeout) => if idle {
                    self.merge_stats();
                    self.housekeeping();
                    last_merge = Instant::now();
                },
            }
        }
        self.merge_stats();
        if let Some(rec) = self.recording.take() {
            finish_recording(rec);
        }
        Ok(())
    }

    /// Polls the queues until something comes (`true`) or `until`. No `spin_loop` hint: a
    /// hypervisor may take a run of PAUSE instructions as lock contention and deschedule the
    /// CPU.
    fn poll_until(&self, until: Instant) -> bool {
        loop {
            if !self.frame_rx.is_empty() || !self.cmd_rx.is_empty() {
                return true;
            }
            if Instant::now() >= until {
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
            ..
        } = self;
        let received = frame.received;
        let mut clients_changed = false;
        pipeline.handle_datagram(frame.peer, &frame.bytes, &mut |e: &Emitted<'_>| {
            let processed = Instant::now();
            Stats::record(
                processed_us,
                processed.duration_since(received).as_micros() as u64,
            );
            // Send before recording: the file write is not on the subscribers' path.
            clients_changed |= fanout.send(e, processed);
            if let Some(rec) = recording.as_mut() {
                rec.push(e);
            }
        });
        if clients_changed {
            self.pipeline.set_wanted(self.fanout.wanted());
        }
        let _ = self.free_tx.try_send(frame.bytes);
    }

    /// Between frames: subscriptions whose lease ended.
    fn housekeeping(&mut self) {
        if self.fanout.expire(Instant::now()) {
            self.pipeline.set_wanted(self.fanout.wanted());
        }
    }

    fn merge_stats(&mut self) {
        let Ok(mut s) = self.stats.lock() else { return };
        s.counters = self.pipeline.counters.clone();
        s.counters.dropped_queue_full = self.queue_dropped.load(Ordering::Relaxed);
        s.streams = self.pipeline.stream_count() as u64;
        s.send = self.fanout.counters.clone();
        (s.poll_hits, s.poll_misses) = (self.poll_hits, self.poll_misses);
        s.clients = self.fanout.len() as u64;
        // Same bounds on both sides, so adding never fails.
        let _ = s.processed_us.add(&self.processed_us);
        self.processed_us.reset();
        let _ = s.sent_us.add(&self.fanout.sent_us);
        self.fanout.sent_us.reset();
    }

    fn command(&mut self, cmd: Cmd) {
        match cmd {
            Cmd::Edit(control, reply) => {
                let r = self
                    .pipeline
                    .handle_edit(&control)
                    .map_err(|e| e.to_string());
                let _ = reply.send(r);
            }
            Cmd::Client(peer, control, reply) => {
                let r = self.fanout.command(peer, &control);
                self.pipeline.set_wanted(self.fanout.wanted());
                let _ = reply.send(r);
            }
            Cmd::SetModel(model, reply) => {
                self.pipeline.set_model(model);
                let _ = reply.send(Ok(()));
            }
            Cmd::RecordStart(path, raw, reply) => {
                if let Some(rec) = self.recording.take() {
                    finish_recording(rec);
                }
                let r =
                    Recording::start(&path, raw.as_deref()).map(|rec| self.recording = Some(rec));
                let _ = reply.send(r.map_err(|e| e.to_string()));
            }
            Cmd::RecordStop(reply) => {
                let r = match self.recording.take() {
                    Some(rec) => rec.finish().map(|_| ()).map_err(|e| e.to_string()),
                    None => Err("no recording in progress".to_string()),
                };
                let _ = reply.send(r);
            }
        }
    }
}

fn finish_recording(rec: Recording) {
    if let Err(e) = rec.finish() {
        tracing::warn!(error = %e, "recording failed");
    }
}

/// Logs the status every `every` until shutdown.
async fn log_stats(stats: Arc<Mutex<Stats>>, every: Duration, shutdown: CancellationToken) {
    let mut tick = tokio::time::interval(every);
    tick.tick().await;
    loop {
        tokio::select! {
            () = shutdown.cancelled() => break,
            _ = tick.tick() => if let Ok(s) = stats.lock() { s.log() },
        }
    }
}

/// Replies to a control message's sender: an `oneshot` answer from the processing thread.
pub(crate) type Answer = oneshot::Sender<Result<(), String>>;
