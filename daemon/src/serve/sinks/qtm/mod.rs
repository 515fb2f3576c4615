//! The QTM server, an [`engine::Sink`]: emoshift looks like Qualisys QTM to RT-protocol
//! clients (QTM Connect for Unreal, Unity, MotionBuilder and Maya, the official SDKs), and the
//! edited face reaches them with no code on their side.
//!
//! - **RT port** (`qtm_server`, default `127.0.0.1:22223`, QTM's little-endian port): one task
//!   accepts clients (at most `qtm_server_max_clients`, each on the control allow-list), one
//!   task per client reads its commands ([`conn`]) and [`hub::Hub`] answers them as QTM does.
//! - **Frames** ([`layout`]): each processed frame updates one labelled-marker list (every
//!   performer's markers, prefixed with the performer's name when there are several); each
//!   streaming client gets it with its components, encoded once per component set, over its
//!   TCP connection ([`outbox`]: a client that does not read loses frames, never the frame
//!   path) or as UDP datagrams to its own address.
//! - **Discovery** (UDP 22226, `qtm_server_discovery`): answered with emoshift's name and the
//!   base port, one below the RT port (22222 for 22223), as QTM answers: the SDKs connect to
//!   the base port + 1 for little endian.
//!
//! `/status` carries `qtm_server/*`: clients, labels, frames sent and dropped, and every
//! refusal counted.

pub mod config;
pub mod conn;
pub mod hub;
pub mod layout;
pub mod outbox;

use std::net::{SocketAddr, TcpListener, UdpSocket};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use anyhow::{Context, Result};
use engine::{Needs, Processed, Sink, StreamKey};
use protocol::qtm::{encode_data_into, Components, DataFrame};
use protocol::StatusValue;
use tokio_util::sync::CancellationToken;

pub use self::config::{QtmServerConfig, RawQtmServer, DEFAULT_QTM_SERVER};
use self::hub::Hub;
use self::outbox::Refused;
use crate::serve::allow::AllowList;

/// How often the status is published and pending output flushed.
const HOUSEKEEPING_EVERY: Duration = Duration::from_millis(250);

/// The server's sockets and shared state, before it runs.
#[derive(Debug)]
pub struct QtmServer {
    /// The frame sink, for the processing thread.
    pub sink: QtmSink,
    /// The accepting and discovery tasks, for the runtime.
    pub tasks: Tasks,
}

/// Binds the RT listener, the UDP frame socket and (when asked) the discovery socket.
///
/// # Errors
/// The RT port cannot be bound (QTM on the same host holds 22223: pick another port).
pub fn open(config: &QtmServerConfig, allow: AllowList) -> Result<QtmServer> {
    let listener = TcpListener::bind(config.addr).with_context(|| {
        format!(
            "binding the QTM server's RT port {} (QTM on this host holds 22223: give \
             --qtm-server another port, e.g. 127.0.0.1:22233)",
            config.addr
        )
    })?;
    listener.set_nonblocking(true)?;
    let udp = UdpSocket::bind(SocketAddr::new(config.addr.ip(), 0))
        .context("binding the QTM server's UDP frame socket")?;
    udp.set_nonblocking(true)?;
    let discovery = match config.discovery {
        Some(addr) => match UdpSocket::bind(addr) {
            Ok(s) => {
                s.set_nonblocking(true)?;
                Some(s)
            }
            Err(e) => {
                tracing::warn!(%addr, error = %e,
                    "QTM discovery not answered: its port is taken (QTM on this host?); \
                     clients can still connect to the RT port by address");
                None
            }
        },
        None => None,
    };
    let hub = Arc::new(Mutex::new(Hub::default()));
    Ok(QtmServer {
        sink: QtmSink {
            hub: Arc::clone(&hub),
            udp,
            generation: 0,
            encoded: Vec::with_capacity(4),
        },
        tasks: Tasks {
            listener,
            discovery,
            hub,
            allow,
            max_clients: config.max_clients,
        },
    })
}

impl QtmServer {
    /// Spawns the accepting task on `tracker` (its status to `on_status`); the frame sink.
    pub fn spawn(
        self,
        on_status: impl FnMut(Vec<(String, StatusValue)>) + Send + 'static,
        tracker: &tokio_util::task::TaskTracker,
        shutdown: &CancellationToken,
    ) -> QtmSink {
        let (tasks, shutdown) = (self.tasks, shutdown.clone());
        tracker.spawn(async move {
            if let Err(e) = tasks.run(on_status, shutdown).await {
                tracing::error!(error = %format!("{e:#}"), "QTM server stopped");
            }
        });
        self.sink
    }
}

/// The accepting and discovery tasks' sockets and the shared hub.
#[derive(Debug)]
pub struct Tasks {
    listener: TcpListener,
    discovery: Option<UdpSocket>,
    hub: Arc<Mutex<Hub>>,
    allow: AllowList,
    max_clients: usize,
}

impl Tasks {
    /// The RT port's address.
    ///
    /// # Errors
    /// The OS cannot tell.
    pub fn local_addr(&self) -> Result<SocketAddr> {
        Ok(self.listener.local_addr()?)
    }

    /// Accepts clients and answers discovery until `shutdown`; gives `on_status` the
    /// `qtm_server/*` pairs a few times a second.
    ///
    /// # Errors
    /// The sockets cannot join the runtime.
    pub async fn run(
        self,
        on_status: impl FnMut(Vec<(String, StatusValue)>) + Send + 'static,
        shutdown: CancellationToken,
    ) -> Result<()> {
        let port = self.listener.local_addr()?.port();
        let listener = tokio::net::TcpListener::from_std(self.listener)?;
        if let Some(d) = self.discovery {
            let d = tokio::net::UdpSocket::from_std(d)?;
            let parts = (Arc::clone(&self.hub), self.allow.clone());
            tokio::spawn(conn::discovery(d, port, parts, shutdown.clone()));
        }
        tokio::spawn(housekeeping(
            Arc::clone(&self.hub),
            on_status,
            shutdown.clone(),
        ));
        let limits = conn::Limits {
            max_clients: self.max_clients,
            allow: self.allow,
        };
        conn::accept(listener, self.hub, limits, shutdown).await;
        Ok(())
    }
}

/// Publishes the status and flushes what clients are owed.
async fn housekeeping(
    hub: Arc<Mutex<Hub>>,
    mut on_status: impl FnMut(Vec<(String, StatusValue)>) + Send,
    shutdown: CancellationToken,
) {
    let mut tick = tokio::time::interval(HOUSEKEEPING_EVERY);
    loop {
        tokio::select! {
            () = shutdown.cancelled() => break,
            _ = tick.tick() => {
                let pairs = match hub.lock() {
                    Ok(mut h) => {
                        let before = h.clients.len();
                        h.clients.retain_mut(|c| c.outbox.flush().is_ok());
                        h.counters.dead += (before - h.clients.len()) as u64;
                        status_pairs(&h)
                    }
                    Err(_) => continue,
                };
                on_status(pairs);
            }
        }
    }
}

/// `/status` pairs: `qtm_server/...`.
pub fn status_pairs(h: &Hub) -> Vec<(String, StatusValue)> {
    let int = |k: &str, v: u64| {
        (
            format!("qtm_server/{k}"),
            StatusValue::Int(i64::try_from(v).unwrap_or(i64::MAX)),
        )
    };
    let c = h.counters;
    let streaming = h.clients.iter().filter(|c| c.stream.is_some()).count();
    let mut out = vec![
        int("clients", h.clients.len() as u64),
        int("streaming", streaming as u64),
        int("labels", h.layout.labels.len() as u64),
        int("connects", c.connects),
        int("refused_full", c.refused_full),
        int("not_allowed", c.not_allowed),
        int("commands", c.commands),
        int("refused_commands", c.refused_commands),
        int("bad_packets", c.bad_packets),
        int("stalled", c.stalled),
        int("dead", c.dead),
        int("frames_sent", c.frames_sent),
        int("frames_dropped", c.frames_dropped),
        int("discoveries", c.discoveries),
    ];
    for (n, client) in h.clients.iter().enumerate() {
        out.push((
            format!("qtm_server/client/{n}/addr"),
            StatusValue::Text(client.peer.to_string()),
        ));
    }
    out
}

/// The frame side, on the processing thread.
#[derive(Debug)]
pub struct QtmSink {
    hub: Arc<Mutex<Hub>>,
    udp: UdpSocket,
    generation: u64,
    /// The frame encoded per component set in use, and whether it is this frame's.
    encoded: Vec<(Components, bool, Vec<u8>)>,
}

/// The frame with `c`, encoded once per frame into its slot of `encoded`.
fn encoded<'a>(
    encoded: &'a mut Vec<(Components, bool, Vec<u8>)>,
    frame: &DataFrame<'_>,
    c: Components,
) -> &'a [u8] {
    let at = match encoded.iter().position(|e| e.0 == c) {
        Some(i) => i,
        None => {
            encoded.push((c, false, Vec::with_capacity(16 * 1024)));
            encoded.len() - 1
        }
    };
    let (_, done, bytes) = &mut encoded[at];
    if !*done {
        encode_data_into(frame, c, bytes);
        *done = true;
    }
    bytes
}

impl Sink for QtmSink {
    fn needs(&self) -> Needs {
        Needs {
            markers: true,
            labels: true,
            time: true,
            input: true,
            ..Needs::NOTHING
        }
    }

    fn handle_frame(&mut self, f: &Processed<'_>) {
        let Ok(mut hub) = self.hub.lock() else {
            return;
        };
        hub.layout.handle_frame(f);
        if hub.layout.generation != self.generation {
            self.generation = hub.layout.generation;
            hub.parameters_changed();
        }
        for e in &mut self.encoded {
            e.1 = false;
        }
        let Hub {
            clients,
            layout,
            counters,
            ..
        } = &mut *hub;
        let frame = layout.frame();
        let rate = layout.rate_hz;
        clients.retain_mut(|c| {
            let Some(s) = &mut c.stream else {
                return true;
            };
            if !s.due(rate) {
                return true;
            }
            let bytes = encoded(&mut self.encoded, &frame, s.components);
            let sent = match s.udp {
                Some(to) => self.udp.send_to(bytes, to).map_err(|_| Refused::Behind),
                None => c.outbox.send_frame(bytes).map(|()| bytes.len()),
            };
            match sent {
                Ok(_) => counters.frames_sent += 1,
                Err(Refused::Behind) => counters.frames_dropped += 1,
                Err(Refused::Dead) => {
                    counters.dead += 1;
                    return false;
                }
            }
            true
        });
    }

    fn handle_gone(&mut self, gone: &[StreamKey]) {
        let Ok(mut hub) = self.hub.lock() else {
            return;
        };
        hub.layout.handle_gone(gone);
        if hub.layout.generation != self.generation {
            self.generation = hub.layout.generation;
            hub.parameters_changed();
        }
    }
}
