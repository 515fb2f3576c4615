//! The NatNet server, an [`engine::Sink`]: emoshift looks like OptiTrack Motive to NatNet
//! clients (OptiTrack's Unreal, Unity and MotionBuilder plugins, the NatNet SDKs, ROS
//! drivers), and the edited face reaches them with no code on their side.
//!
//! - **Command port** (`natnet_server`, default `127.0.0.1:1510`): a task answering connect,
//!   model definitions, keep-alive, echo and request strings as Motive does ([`session`]).
//! - **Data port** (PORT + 1): frames go out from it, to each unicast client that keeps its
//!   session alive (at its own bitstream, 3.x or 4.x), or to the multicast group
//!   (`natnet_server_multicast`) on the chosen interface.
//! - **Frames** ([`frame`]): one NAT_FRAMEOFDATA per processed frame, encoded once per
//!   bitstream in use and sent straight from the processing thread (a full socket buffer drops
//!   the datagram and counts it: the frame path never waits on a client).
//!
//! `/status` carries `natnet_server/*`: the clients with their bitstreams and leases, frames
//! and bytes sent, and every refusal counted.

pub mod config;
pub mod counters;
pub mod frame;
pub mod session;
pub mod status;

use std::io::ErrorKind;
use std::net::{SocketAddr, UdpSocket};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime};

use anyhow::{Context, Result};
use engine::{Needs, Processed, Sink, StreamKey};
use protocol::natnet::{encode_frame_into, FrameOfData, NatNetVersion};
use protocol::StatusValue;
use socket2::{Domain, Protocol, Socket, Type};
use tokio_util::sync::CancellationToken;

pub use self::config::{NatNetServerConfig, RawNatNetServer, DEFAULT_NATNET_SERVER};
use self::frame::Streams;
use self::session::{Identity, Session};
use self::status::status_pairs;
use crate::serve::allow::AllowList;

/// How often leases are checked and the status is published.
const HOUSEKEEPING_EVERY: Duration = Duration::from_secs(1);

/// The server clock: microseconds since the Unix epoch ([`session::CLOCK_HZ`]).
pub fn ticks_now() -> u64 {
    SystemTime::now()
        .duration_since(SystemTime::UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_micros()).unwrap_or(u64::MAX))
}

/// The server's sockets and shared state, before it runs.
#[derive(Debug)]
pub struct NatNetServer {
    /// The frame sink, for the processing thread.
    pub sink: NatNetSink,
    /// The command task, for the runtime.
    pub commands: Commands,
}

/// Binds the command and data sockets.
///
/// # Errors
/// A socket that cannot be bound (a port in use: Motive on the same host has 1510/1511).
pub fn open(
    config: &NatNetServerConfig,
    allow: AllowList,
    max_markers: usize,
) -> Result<NatNetServer> {
    let command = std::net::UdpSocket::bind(config.command).with_context(|| {
        format!(
            "binding the NatNet server's command port {} (Motive on this host holds 1510: \
             give --natnet-server another port, e.g. 127.0.0.1:1512)",
            config.command
        )
    })?;
    command.set_nonblocking(true)?;
    let data = data_socket(config)?;
    let identity = Identity {
        app_version: app_version(),
        data_port: data.local_addr()?.port(),
        multicast: config.multicast,
        version: config.version,
    };
    let session = Arc::new(Mutex::new(Session::new(
        identity,
        allow,
        config.max_clients,
    )));
    let commands = Commands {
        socket: tokio::net::UdpSocket::from_std(command)?,
        session: Arc::clone(&session),
    };
    Ok(NatNetServer {
        sink: NatNetSink {
            session,
            data,
            streams: Streams::new(max_markers, config.raw),
            generation: 0,
            encoded: Vec::with_capacity(4),
            next_housekeeping: Instant::now(),
        },
        commands,
    })
}

/// The data socket: PORT + 1 on the command address (any port when that is 0, or when
/// frames are multicast: the group's port is the clients'), multicast out on the interface,
/// looped back to local clients, TTL 1 (0 on loopback: nothing leaves the host).
fn data_socket(config: &NatNetServerConfig) -> Result<UdpSocket> {
    let addr = match config.multicast {
        Some(_) => SocketAddr::new(config.command.ip(), 0),
        None => config.data_addr(),
    };
    let s = Socket::new(Domain::for_address(addr), Type::DGRAM, Some(Protocol::UDP))?;
    if let (Some(_), SocketAddr::V4(_)) = (config.multicast, addr) {
        s.set_multicast_if_v4(&config.interface)?;
        s.set_multicast_loop_v4(true)?;
        let ttl = if config.interface.is_loopback() { 0 } else { 1 };
        s.set_multicast_ttl_v4(ttl)?;
    }
    s.bind(&addr.into())
        .with_context(|| format!("binding the NatNet server's data port {addr}"))?;
    s.set_nonblocking(true)?;
    Ok(s.into())
}

/// The command task's socket and the shared session.
#[derive(Debug)]
pub struct Commands {
    socket: tokio::net::UdpSocket,
    session: Arc<Mutex<Session>>,
}

impl Commands {
    /// The command port's address.
    ///
    /// # Errors
    /// The OS cannot tell.
    pub fn local_addr(&self) -> Result<SocketAddr> {
        Ok(self.socket.local_addr()?)
    }

    /// Answers clients until `shutdown`; checks leases and gives `on_status` the
    /// `natnet_server/*` pairs once a second.
    pub async fn run(
        self,
        mut on_status: impl FnMut(Vec<(String, StatusValue)>) + Send,
        shutdown: CancellationToken,
    ) {
        let mut buf = vec![0u8; 65_536];
        let mut out = Vec::with_capacity(65_536);
        let mut tick = tokio::time::interval(HOUSEKEEPING_EVERY);
        loop {
            tokio::select! {
                () = shutdown.cancelled() => break,
                _ = tick.tick() => {
                    let pairs = match self.session.lock() {
                        Ok(mut s) => {
                            s.poll_expired(Instant::now());
                            status_pairs(&s)
                        }
                        Err(_) => continue,
                    };
                    on_status(pairs);
                }
                r = self.socket.recv_from(&mut buf) => {
                    let Ok((n, peer)) = r else { continue };
                    let reply = match self.session.lock() {
                        Ok(mut s) => s.handle_command(Instant::now(), ticks_now(), (peer, &buf[..n]), &mut out),
                        Err(_) => false,
                    };
                    if reply {
                        let _ = self.socket.send_to(&out, peer).await;
                    }
                }
            }
        }
    }
}

/// The frame side, on the processing thread.
#[derive(Debug)]
pub struct NatNetSink {
    session: Arc<Mutex<Session>>,
    data: UdpSocket,
    streams: Streams,
    generation: u64,
    /// The frame encoded per bitstream in use, and whether it is this frame's (empty: not
    /// encodable).
    encoded: Vec<(NatNetVersion, bool, Vec<u8>)>,
    next_housekeeping: Instant,
}

/// The frame in bitstream `v`, encoded once per frame into its slot of `encoded`.
fn encoded<'a>(
    encoded: &'a mut Vec<(NatNetVersion, bool, Vec<u8>)>,
    frame: &FrameOfData,
    v: NatNetVersion,
) -> Option<&'a [u8]> {
    let at = match encoded.iter().position(|e| e.0 == v) {
        Some(i) => i,
        None => {
            encoded.push((v, false, Vec::with_capacity(16 * 1024)));
            encoded.len() - 1
        }
    };
    let (_, done, bytes) = &mut encoded[at];
    if !*done {
        if encode_frame_into(frame, v, bytes).is_err() {
            bytes.clear();
        }
        *done = true;
    }
    (!bytes.is_empty()).then_some(bytes.as_slice())
}

impl Sink for NatNetSink {
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
        let now = Instant::now();
        self.streams.handle_frame(f, ticks_now());
        let session = Arc::clone(&self.session);
        let Ok(mut session) = session.lock() else {
            return;
        };
        if self.streams.generation != self.generation {
            self.generation = self.streams.generation;
            session.defs = self.streams.defs();
            session.rate_hz = f.rate_hz() as f32;
        }
        if now >= self.next_housekeeping {
            self.next_housekeeping = now + HOUSEKEEPING_EVERY;
            session.poll_expired(now);
        }
        // A new frame: the last one's encodings are stale.
        for e in &mut self.encoded {
            e.1 = false;
        }
        if let Some((group, v)) = session.multicast() {
            let sent = match encoded(&mut self.encoded, &self.streams.frame, v) {
                Some(bytes) => send(&self.data, bytes, group.into()),
                None => {
                    session.counters.encode_errors += 1;
                    None
                }
            };
            session.handle_multicast(sent);
            return;
        }
        let mut i = 0;
        while let Some(c) = session.client(i) {
            let (addr, v) = (c.addr, c.wants);
            let sent = match encoded(&mut self.encoded, &self.streams.frame, v) {
                Some(bytes) => send(&self.data, bytes, addr),
                None => {
                    session.counters.encode_errors += 1;
                    None
                }
            };
            let before = session.client_count();
            session.handle_send(i, sent, now);
            if session.client_count() == before {
                i += 1;
            }
        }
    }

    fn handle_gone(&mut self, gone: &[StreamKey]) {
        self.streams.handle_gone(gone);
        if self.streams.generation != self.generation {
            self.generation = self.streams.generation;
            if let Ok(mut s) = self.session.lock() {
                s.defs = self.streams.defs();
            }
        }
    }
}

/// Sends one datagram; `Some(len)` when it went out, `Some(0)` when a full send buffer
/// dropped it (counted, but not the client's failure), `None` on a send error.
fn send(socket: &UdpSocket, bytes: &[u8], to: SocketAddr) -> Option<usize> {
    match socket.send_to(bytes, to) {
        Ok(n) => Some(n),
        Err(e) if e.kind() == ErrorKind::WouldBlock => Some(0),
        Err(_) => None,
    }
}

/// emoshift's version as NatNet's four bytes.
pub fn app_version() -> [u8; 4] {
    let mut v = [0u8; 4];
    for (slot, part) in v.iter_mut().zip(env!("CARGO_PKG_VERSION").split('.')) {
        *slot = part.parse().unwrap_or(0);
    }
    v
}
