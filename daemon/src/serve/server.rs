//! The only module that awaits. Tasks:
//!
//! - **receive**: frame socket → pooled buffer → bounded crossbeam channel; when full the
//!   oldest frame is dropped and counted (latest frame wins);
//! - **processing** (one blocking thread, [`Processing`]): [`Pipeline`] per frame, then the
//!   encoded bytes straight to every subscriber ([`Fanout`]), control commands (edits,
//!   subscriptions, models, recordings) between frames, recording;
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
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;

use super::allow::AllowList;
use super::command::Request;
use super::control::{self, ControlCtx, Guard};
use super::monitor::{Board, Feed};
use super::processing::{Channels, InFrame, Processing, Shared};
use super::sender::Fanout;
use super::stats::Stats;
use super::Config;
use crate::engine::pipeline::{Pipeline, PipelineConfig};
use crate::engine::streams::Performer;

/// Pooled buffers kept for received datagrams.
const POOL: usize = 256;

/// A server with its sockets bound and its models loaded; [`Bound::run`] serves.
#[derive(Debug)]
pub struct Bound {
    frames: UdpSocket,
    /// The frame socket again, for telling a source why its datagram was refused.
    replies: std::net::UdpSocket,
    control: UdpSocket,
    config: Config,
    model: Arc<IcaModel>,
    performers: Vec<Performer>,
    /// The NatNet source's sockets, when one is configured.
    natnet: Option<super::natnet::Link>,
    /// The monitor page's listener, when the page is served.
    monitor: Option<tokio::net::TcpListener>,
}

/// Binds both sockets and loads the models, so that a test learns the addresses before frames
/// flow (`127.0.0.1:0` gives free ports).
///
/// # Errors
/// A socket that cannot be bound or a model that cannot be loaded.
pub async fn bind(config: Config) -> Result<Bound> {
    let model = super::load_model(config.model.clone(), config.max_model_bytes).await?;
    bind_with(config, model).await
}

/// [`bind`] with the default model given instead of read from `config.model` (bench, tests).
///
/// # Errors
/// A socket that cannot be bound or a performer model that cannot be loaded.
pub async fn bind_with(config: Config, model: IcaModel) -> Result<Bound> {
    let model = Arc::new(model);
    let mut performers = Vec::with_capacity(config.performers.len());
    for p in config.performers.iter().cloned() {
        let model = match &p.model {
            Some(path) => Some(Arc::new(
                super::load_model(path.clone(), config.max_model_bytes).await?,
            )),
            None => None,
        };
        performers.push(p.with_model(model));
    }
    let frames = super::net::bind_receiver_std(config.listen)
        .with_context(|| format!("binding the frame socket {}", config.listen))?;
    let replies = frames.try_clone().context("cloning the frame socket")?;
    replies.set_nonblocking(true)?;
    frames.set_nonblocking(true)?;
    let frames = UdpSocket::from_std(frames)?;
    let control = UdpSocket::bind(config.control)
        .await
        .with_context(|| format!("binding the control socket {}", config.control))?;
    let natnet = config
        .natnet
        .clone()
        .map(super::natnet::Link::open)
        .transpose()?;
    let monitor = match config.monitor {
        Some(addr) => Some(super::monitor::bind(addr).await?),
        None => None,
    };
    Ok(Bound {
        monitor,
        frames,
        replies,
        control,
        config,
        model,
        performers,
        natnet,
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

    /// The monitor page's address, when it is served.
    ///
    /// # Errors
    /// The OS cannot tell.
    pub fn monitor_addr(&self) -> Result<Option<SocketAddr>> {
        Ok(self.monitor.as_ref().map(|l| l.local_addr()).transpose()?)
    }

    /// Serves until `shutdown` is cancelled, then drains and returns.
    ///
    /// # Errors
    /// A task that failed or panicked.
    pub async fn run(self, shutdown: CancellationToken) -> Result<()> {
        let tracker = TaskTracker::new();
        let stats = Arc::new(Mutex::new(Stats::new()));
        if let Ok(mut s) = stats.lock() {
            s.model = self.config.model.display().to_string();
        }
        let (frame_tx, frame_rx) = crossbeam_channel::bounded::<InFrame>(self.config.queue);
        let (free_tx, free_rx) = crossbeam_channel::bounded::<Vec<u8>>(POOL);
        let (cmd_tx, cmd_rx) = crossbeam_channel::bounded::<Request>(64);
        let shared = Shared {
            stats: Arc::clone(&stats),
            queue_dropped: Arc::new(AtomicU64::new(0)),
            not_allowed: Arc::new(AtomicU64::new(0)),
            replies: None,
            monitor: None,
        };
        let queue = Queue {
            tx: frame_tx,
            rx: frame_rx.clone(),
            free: free_rx,
            dropped: Arc::clone(&shared.queue_dropped),
        };
        let admission = Admission {
            allow: self.config.frames_allow.clone(),
            refused: Arc::clone(&shared.not_allowed),
        };
        let channels = Channels {
            frames: frame_rx,
            free: free_tx,
            commands: cmd_rx,
        };
        let ctx = ControlCtx {
            socket: Arc::new(self.control),
            cmd_tx,
            stats: Arc::clone(&stats),
            model_path: Arc::new(Mutex::new(self.config.model.clone())),
            model: Arc::new(Mutex::new(Arc::clone(&self.model))),
            tracker: tracker.clone(),
            guard: Arc::new(Guard::new(&self.config)),
        };
        let every = self.config.stats_interval;
        let frames = self.frames;
        let board = Arc::new(Board::new());
        if let Some(listener) = self.monitor {
            let token = self.config.monitor_token.clone();
            let parts = (Arc::clone(&board), ctx.clone(), Arc::clone(&stats));
            super::monitor::spawn(listener, token, parts, &tracker, shutdown.clone())?;
        }
        let feed = self.config.monitor.map(|_| Feed::new(board));
        let processing = processing_thread(
            (self.model, self.performers, self.config),
            channels,
            Shared {
                replies: Some(self.replies),
                monitor: feed,
                ..shared
            },
        )?;
        let processing = tracker.spawn_blocking(move || processing.run());
        if let Some(link) = self.natnet {
            let queue = queue.clone();
            tracker.spawn(super::natnet::source::run(
                link,
                queue,
                Arc::clone(&stats),
                shutdown.clone(),
            ));
        }
        tracker.spawn(receive(frames, queue, admission, shutdown.clone()));
        tracker.spawn(control::run(ctx.clone(), shutdown.clone()));
        tracker.spawn(control::reload_on_sighup(ctx, shutdown.clone()));
        tracker.spawn(log_stats(stats, every, shutdown.clone()));
        tracker.close();
        let result = processing.await;
        tracker.wait().await;
        result.context("processing thread panicked")
    }
}

/// The processing thread's state: one engine over the models, the subscribers' sockets.
fn processing_thread(
    (model, performers, config): (Arc<IcaModel>, Vec<Performer>, Config),
    channels: Channels,
    shared: Shared,
) -> Result<Processing> {
    let pipeline = Pipeline::new(
        model,
        performers,
        PipelineConfig {
            lowpass_s: config.lowpass_s,
            ..PipelineConfig::default()
        },
    );
    let fanout = Fanout::new(&config)?;
    Ok(Processing::new(
        pipeline,
        fanout,
        config.poll_window,
        channels,
        shared,
    ))
}

/// The processing queue's ends as a receiving task uses them.
#[derive(Clone)]
pub(super) struct Queue {
    tx: Sender<InFrame>,
    /// To drop the oldest frame when full.
    rx: Receiver<InFrame>,
    /// Buffers handed back by the processing thread.
    free: Receiver<Vec<u8>>,
    /// Frames dropped because the queue was full.
    dropped: Arc<AtomicU64>,
}

/// Which sources may send frames.
struct Admission {
    allow: AllowList,
    /// Datagrams from other sources, dropped.
    refused: Arc<AtomicU64>,
}

/// Receive task: datagrams from allowed sources into the bounded queue, latest frame wins.
async fn receive(
    socket: UdpSocket,
    queue: Queue,
    admission: Admission,
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
                    tracing::trace!(target: "emoshift", error = %e, "frame socket receive error");
                    continue;
                }
            },
        };
        if !admission.allow.allows(peer.ip()) {
            admission.refused.fetch_add(1, Ordering::Relaxed);
            continue;
        }
        let mut bytes = queue.buffer();
        bytes.extend_from_slice(&buf[..len]);
        let item = InFrame {
            peer,
            bytes,
            received: Instant::now(),
            natnet: None,
        };
        if !queue.push(item) {
            return;
        }
    }
}

impl Queue {
    /// An empty buffer for a datagram: a pooled one handed back by the processing thread.
    pub(super) fn buffer(&self) -> Vec<u8> {
        let mut bytes = self.free.try_recv().unwrap_or_default();
        bytes.clear();
        bytes
    }

    /// Queues `item` for the processing thread, dropping (and counting) the oldest frame
    /// when full: latest frame wins. `false` once the processing thread is gone.
    pub(super) fn push(&self, mut item: InFrame) -> bool {
        loop {
            match self.tx.try_send(item) {
                Ok(()) => return true,
                Err(crossbeam_channel::TrySendError::Full(back)) => {
                    item = back;
                    if self.rx.try_recv().is_ok() {
                        self.dropped.fetch_add(1, Ordering::Relaxed);
                    }
                }
                Err(crossbeam_channel::TrySendError::Disconnected(_)) => return false,
            }
        }
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
