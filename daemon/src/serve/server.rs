//! Binds the sockets and runs the tasks (the only module that awaits, with `control`):
//!
//! - **sources** ([`super::sources`]): the OSC frame socket, read by the processing thread
//!   itself; the NatNet and QTM links when configured, one task each, each frame into the
//!   processing [`Queue`] (bounded; when full the oldest frame is dropped and counted: latest
//!   frame wins);
//! - **processing** (one blocking thread, [`Processing`]): [`Pipeline`] per frame, then every
//!   sink ([`Outputs`]: the OSC subscribers first, the recording, the monitor feed); control
//!   commands (edits, subscriptions, models, recordings) between frames;
//! - **control**: decodes control messages and answers them;
//! - **stats**: logs the counters every few seconds; **SIGHUP** reloads the model.
//!
//! Shutdown: the token stops the sources and control, and rings the processing thread, which
//! stops reading the frame socket, drains the queue, sends what it processes and closes the
//! recording.

use std::net::SocketAddr;
use std::sync::{Arc, Mutex};

use anyhow::{Context, Result};
use engine::pipeline::PipelineConfig;
use engine::{Performer, SourceFrame};
use ica_core::model::IcaModel;
use tokio::net::UdpSocket;
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;

use super::command::Request;
use super::control;
use super::monitor::{Board, Feed};
use super::processing::{Inbox, Inputs, Processing, Shared};
use super::queue::Queue;
use super::sinks::natnet::{self as natnet_server, NatNetServer, NatNetSink};
use super::sinks::qtm::{self as qtm_server, QtmServer, QtmSink};
use super::sources::natnet::{Link, NatNetStatus};
use super::sources::qtm::{self, QtmConfig, QtmStatus};
use super::sources::{Arrival, InputCounters};
use super::stats::{log_stats, model_name, status_into, Stats};
use super::Config;

mod assemble;
use assemble::{control_ctx, osc_intake, outputs, processing_pipeline, ring_on_shutdown};

type QtmInput = (QtmConfig, Arc<InputCounters>);

/// A server with its sockets bound and its models loaded; [`Bound::run`] serves.
#[derive(Debug)]
pub struct Bound {
    /// The OSC frame socket (blocking mode is the processing thread's to set).
    frames: std::net::UdpSocket,
    /// The frame socket again, for telling a source why its datagram was refused.
    replies: std::net::UdpSocket,
    control: UdpSocket,
    control_news: std::net::UdpSocket,
    config: Config,
    /// The default model; `None`: frames pass through until one is loaded.
    model: Option<Arc<IcaModel>>,
    performers: Vec<Performer>,
    /// The NatNet source's sockets, when one is configured, and its counters.
    natnet: Option<(Link, Arc<InputCounters>)>,
    /// The monitor page's listener, when the page is served.
    monitor: Option<tokio::net::TcpListener>,
    /// The NatNet server's sockets, when one is configured.
    natnet_server: Option<NatNetServer>,
    /// The QTM server's sockets, when one is configured.
    qtm_server: Option<QtmServer>,
}

/// Binds both sockets and loads the models, so that a test learns the addresses before frames
/// flow (`127.0.0.1:0` gives free ports).
///
/// # Errors
/// A socket that cannot be bound or a model that cannot be loaded.
pub async fn bind(config: Config) -> Result<Bound> {
    let model = match config.model.clone() {
        Some(path) => Some(super::load_model(path, config.max_model_bytes).await?),
        None => None,
    };
    bind_model(config, model.map(Arc::new)).await
}

/// [`bind`] with the default model given instead of read from `config.model` (bench, tests).
///
/// # Errors
/// A socket that cannot be bound or a performer model that cannot be loaded.
pub async fn bind_with(config: Config, model: IcaModel) -> Result<Bound> {
    bind_model(config, Some(Arc::new(model))).await
}

/// [`bind`] with the default model, if any, loaded.
async fn bind_model(config: Config, model: Option<Arc<IcaModel>>) -> Result<Bound> {
    let performers = load_performers(&config).await?;
    let frames = super::net::bind_receiver_std(config.listen)
        .with_context(|| format!("binding the frame socket {}", config.listen))?;
    let replies = frames.try_clone().context("cloning the frame socket")?;
    replies.set_nonblocking(true)?;
    let (control, control_news) = bind_control(config.control)?;
    let natnet = match config.natnet.clone() {
        Some(n) => {
            let counters = Arc::new(InputCounters::named("natnet"));
            Some((Link::open(n, Arc::clone(&counters))?, counters))
        }
        None => None,
    };
    let monitor = match config.monitor {
        Some(addr) => Some(super::monitor::bind(addr).await?),
        None => None,
    };
    let natnet_server = match &config.natnet_server {
        Some(n) => {
            let max_markers = PipelineConfig::default().max_markers;
            Some(natnet_server::open(
                n,
                config.control_allow.clone(),
                max_markers,
            )?)
        }
        None => None,
    };
    let qtm_server = match &config.qtm_server {
        Some(q) => Some(qtm_server::open(q, config.control_allow.clone())?),
        None => None,
    };
    Ok(Bound {
        monitor,
        natnet_server,
        qtm_server,
        frames,
        replies,
        control,
        control_news,
        config,
        model,
        performers,
        natnet,
    })
}

/// Each performer with its own model loaded, when it names one.
async fn load_performers(config: &Config) -> Result<Vec<Performer>> {
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
    Ok(performers)
}

/// The control socket, and a clone of it: the recording's way to tell a controller news it did
/// not ask for (a full disk), from the address its answers come from.
fn bind_control(addr: SocketAddr) -> Result<(UdpSocket, std::net::UdpSocket)> {
    let control = std::net::UdpSocket::bind(addr)
        .with_context(|| format!("binding the control socket {addr}"))?;
    let control_news = control.try_clone().context("cloning the control socket")?;
    control_news.set_nonblocking(true)?;
    control.set_nonblocking(true)?;
    Ok((UdpSocket::from_std(control)?, control_news))
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

    /// The NatNet server's command address, when it is served.
    ///
    /// # Errors
    /// The OS cannot tell.
    pub fn natnet_server_addr(&self) -> Result<Option<SocketAddr>> {
        self.natnet_server
            .as_ref()
            .map(|n| n.commands.local_addr())
            .transpose()
    }

    /// The QTM server's RT address, when it is served.
    ///
    /// # Errors
    /// The OS cannot tell.
    pub fn qtm_server_addr(&self) -> Result<Option<SocketAddr>> {
        self.qtm_server
            .as_ref()
            .map(|q| q.tasks.local_addr())
            .transpose()
    }

    /// Serves until `shutdown` is cancelled, then drains and returns.
    ///
    /// # Errors
    /// A task that failed or panicked.
    pub async fn run(self, shutdown: CancellationToken) -> Result<()> {
        let tracker = TaskTracker::new();
        let osc = Arc::new(InputCounters::named("osc"));
        let qtm = (self.config.qtm.clone()).map(|q| (q, Arc::new(InputCounters::named("qtm"))));
        let stats = new_stats(&self.config, &osc, (&self.natnet, &qtm));
        let shared = Shared::new(Arc::clone(&stats));
        let max_markers = PipelineConfig::default().max_markers;
        let (inbox, bell) = Inbox::new(self.frames).context("waiting on the frame socket")?;
        let (queue, ends) = Queue::new(
            self.config.queue,
            max_markers,
            Arc::clone(&shared.queue_dropped),
            bell.clone(),
        );
        let (cmd_tx, cmd_rx) = crossbeam_channel::bounded::<Request>(64);
        let commands = (cmd_tx, bell.clone());
        let ctx = control_ctx(
            self.control,
            commands,
            &stats,
            (&self.config, &self.model),
            &tracker,
        );
        let board = Arc::new(Board::new());
        if let Some(listener) = self.monitor {
            let token = self.config.monitor_token.clone();
            let parts = (Arc::clone(&board), ctx.clone(), Arc::clone(&stats));
            super::monitor::spawn(listener, token, parts, &tracker, shutdown.clone())?;
        }
        let osc = osc_intake(&self.config, &shared, self.replies, osc, max_markers);
        let feed = self.config.monitor.map(|_| Feed::new(board));
        let pipeline = processing_pipeline(self.model, self.performers, &self.config);
        let servers = (self.natnet_server, self.qtm_server);
        let sinks = spawn_servers(servers, &stats, &tracker, &shutdown);
        let outputs = outputs(&self.config, feed, sinks, self.control_news)?;
        let inputs = Inputs {
            inbox,
            osc,
            queue: ends,
            commands: cmd_rx,
            shutdown: shutdown.clone(),
        };
        let (engine, window) = ((pipeline, outputs), self.config.poll_window);
        let processing = Processing::new(engine, window, inputs, shared);
        let processing = tracker.spawn_blocking(move || processing.run());
        ring_on_shutdown(bell, &tracker, &shutdown);
        let link = self.natnet.map(|n| n.0);
        spawn_sources((link, qtm), (queue, &stats), &tracker, &shutdown);
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

/// The shared stats, with the model's file and each source's counters.
fn new_stats(
    config: &Config,
    osc: &Arc<InputCounters>,
    (natnet, qtm): (&Option<(Link, Arc<InputCounters>)>, &Option<QtmInput>),
) -> Arc<Mutex<Stats>> {
    let mut stats = Stats::new();
    stats.model = model_name(config.model.as_deref());
    stats.inputs.push(Arc::clone(osc));
    stats
        .inputs
        .extend(natnet.as_ref().map(|n| Arc::clone(&n.1)));
    stats.inputs.extend(qtm.as_ref().map(|q| Arc::clone(&q.1)));
    Arc::new(Mutex::new(stats))
}

/// The NatNet and QTM servers' tasks when configured, their status into `/status`; their
/// frame sinks.
fn spawn_servers(
    (natnet, qtm): (Option<NatNetServer>, Option<QtmServer>),
    stats: &Arc<Mutex<Stats>>,
    tracker: &TaskTracker,
    shutdown: &CancellationToken,
) -> (Option<NatNetSink>, Option<QtmSink>) {
    let natnet = natnet.map(|server| {
        let on_status = status_into(stats, "natnet_server");
        tracker.spawn(server.commands.run(on_status, shutdown.clone()));
        server.sink
    });
    let qtm = qtm.map(|q| q.spawn(status_into(stats, "qtm_server"), tracker, shutdown));
    (natnet, qtm)
}

/// The task of every source but the OSC frame socket (the processing thread reads that), its
/// frames into `queue`: the NatNet and QTM links when configured (their status into `stats`).
/// A new source is one more task here.
fn spawn_sources(
    (natnet_link, qtm): (Option<Link>, Option<QtmInput>),
    (queue, stats): (Queue, &Arc<Mutex<Stats>>),
    tracker: &TaskTracker,
    shutdown: &CancellationToken,
) {
    if let Some(link) = natnet_link {
        let stats = Arc::clone(stats);
        tracker.spawn(natnet(link, queue.clone(), stats, shutdown.clone()));
    }
    if let Some((config, counters)) = qtm {
        let (stats, queue, shutdown) = (Arc::clone(stats), queue.clone(), shutdown.clone());
        tracker.spawn(async move {
            let mut sink = |frame: &SourceFrame<'_>, arrival: &Arrival| {
                queue.push(frame, arrival);
            };
            let mut on_status = |st: &QtmStatus| {
                if let Ok(mut s) = stats.lock() {
                    s.set_source_status("qtm", st.pairs());
                }
            };
            let _ = qtm::run(config, counters, shutdown, &mut sink, &mut on_status).await;
        });
    }
}

/// The NatNet link's task: its frames into the queue, its status into `/status`.
async fn natnet(link: Link, queue: Queue, stats: Arc<Mutex<Stats>>, shutdown: CancellationToken) {
    let mut sink = |frame: &SourceFrame<'_>, arrival: &Arrival| {
        queue.push(frame, arrival);
    };
    let mut on_status = |status: &NatNetStatus| {
        if let Ok(mut s) = stats.lock() {
            s.set_source_status("natnet", status.pairs());
        }
    };
    if let Err(e) = link.run(shutdown, &mut sink, &mut on_status).await {
        tracing::error!(target: "emoshift", error = %format!("{e:#}"), "natnet: the source stopped");
    }
}
