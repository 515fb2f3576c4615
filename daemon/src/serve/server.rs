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

use super::command::Request;
use super::control::{self, ControlCtx};
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
    control: UdpSocket,
    config: Config,
    model: Arc<IcaModel>,
    performers: Vec<Performer>,
}

/// Binds both sockets and loads the models, so that a test learns the addresses before frames
/// flow (`127.0.0.1:0` gives free ports).
///
/// # Errors
/// A socket that cannot be bound or a model that cannot be loaded.
pub async fn bind(config: Config) -> Result<Bound> {
    let model = super::load_model(config.model.clone()).await?;
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
            Some(path) => Some(Arc::new(super::load_model(path.clone()).await?)),
            None => None,
        };
        performers.push(p.with_model(model));
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
        let (cmd_tx, cmd_rx) = crossbeam_channel::bounded::<Request>(64);

        let current_model = Arc::new(Mutex::new(Arc::clone(&self.model)));
        let pipeline = Pipeline::new(
            self.model,
            self.performers,
            PipelineConfig {
                lowpass_s: self.config.lowpass_s,
                ..PipelineConfig::default()
            },
        );
        let processing = Processing::new(
            pipeline,
            Fanout::new(&self.config)?,
            self.config.poll_window,
            Channels {
                frames: frame_rx.clone(),
                free: free_tx,
                commands: cmd_rx,
            },
            Shared {
                stats: Arc::clone(&stats),
                queue_dropped: Arc::clone(&queue_dropped),
            },
        );
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
            model: current_model,
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
        result.context("processing thread panicked")
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
