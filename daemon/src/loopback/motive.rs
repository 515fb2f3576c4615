//! A Motive stand-in: a NatNet server on loopback for the bench and the end-to-end tests. It
//! answers connect (server info), model definition requests, echo (its clock: µs since an
//! epoch the caller shares, 1 MHz), `FrameRate`, and streams the frames it is given to a
//! multicast group on loopback (TTL 0: nothing leaves the host) or to every client that
//! connected (unicast). Encoded by `protocol::natnet`, as a real server's frames are decoded.

use std::net::{Ipv4Addr, SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use protocol::natnet::{
    decode_packet, encode_echo_response_into, encode_frame_into, encode_model_defs_into,
    encode_server_info_into, ConnectionInfo, EchoResponse, FrameOfData, MessageId, ModelDefs,
    NatNetVersion, Packet, ServerInfo,
};
use socket2::{Domain, Protocol, Socket, Type};

/// The stand-in's clock rate: ticks are microseconds.
pub const CLOCK_HZ: u64 = 1_000_000;

/// How to start a [`Motive`].
#[derive(Debug, Clone)]
pub struct MotiveOptions {
    /// Command address (`127.0.0.1:0` for any port; a fixed port to restart on the same one).
    pub command: SocketAddr,
    /// Multicast group and port frames go to; `None`: unicast to each client.
    pub multicast: Option<SocketAddr>,
    /// NatNet version of frames and model definitions.
    pub version: NatNetVersion,
    /// The model definitions it describes.
    pub defs: ModelDefs,
    /// Its clock's epoch (share it with the receivers to measure latency from capture).
    pub epoch: Instant,
    /// The rate `FrameRate` answers.
    pub rate_hz: f32,
}

/// What the command thread shares.
#[derive(Debug, Default)]
struct Shared {
    clients: Mutex<Vec<SocketAddr>>,
    stop: AtomicBool,
}

/// A running stand-in.
#[derive(Debug)]
pub struct Motive {
    command_addr: SocketAddr,
    sender: UdpSocket,
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    options: MotiveOptions,
    buf: Vec<u8>,
}

impl Motive {
    /// Binds the command socket and starts answering.
    ///
    /// # Errors
    /// A socket that cannot be bound.
    pub fn start(options: MotiveOptions) -> Result<Motive> {
        let command = UdpSocket::bind(options.command).context("binding the stand-in")?;
        command.set_read_timeout(Some(Duration::from_millis(20)))?;
        let command_addr = command.local_addr()?;
        let sender = Socket::new(Domain::IPV4, Type::DGRAM, Some(Protocol::UDP))?;
        sender.set_multicast_if_v4(&Ipv4Addr::LOCALHOST)?;
        sender.set_multicast_ttl_v4(0)?;
        sender.set_multicast_loop_v4(true)?;
        sender.bind(&SocketAddr::from((Ipv4Addr::LOCALHOST, 0)).into())?;
        let shared = Arc::new(Shared::default());
        let answering = Answering {
            socket: command,
            shared: Arc::clone(&shared),
            options: options.clone(),
        };
        let thread = std::thread::Builder::new()
            .name("motive-stand-in".into())
            .spawn(move || answering.run())
            .context("starting the stand-in")?;
        Ok(Motive {
            command_addr,
            sender: sender.into(),
            shared,
            thread: Some(thread),
            options,
            buf: Vec::with_capacity(64 * 1024),
        })
    }

    /// Where clients connect.
    pub fn command_addr(&self) -> SocketAddr {
        self.command_addr
    }

    /// Clients that connected.
    pub fn clients(&self) -> usize {
        self.shared.clients.lock().map_or(0, |c| c.len())
    }

    /// The stand-in's clock at `at`, in ticks (µs since the epoch).
    pub fn ticks(&self, at: Instant) -> u64 {
        at.saturating_duration_since(self.options.epoch).as_micros() as u64
    }

    /// Encodes `frame` and streams it: to the group, or to every client. Returns datagrams
    /// sent.
    ///
    /// # Errors
    /// A frame that does not encode.
    pub fn send(&mut self, frame: &FrameOfData) -> Result<usize> {
        encode_frame_into(frame, self.options.version, &mut self.buf)?;
        if let Some(group) = self.options.multicast {
            return Ok(usize::from(self.sender.send_to(&self.buf, group).is_ok()));
        }
        let clients = self
            .shared
            .clients
            .lock()
            .map(|c| c.clone())
            .unwrap_or_default();
        Ok(clients
            .iter()
            .filter(|c| self.sender.send_to(&self.buf, c).is_ok())
            .count())
    }

    /// Stops answering and closes its sockets.
    pub fn stop(mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Motive {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
    }
}

/// The command thread.
struct Answering {
    socket: UdpSocket,
    shared: Arc<Shared>,
    options: MotiveOptions,
}

impl Answering {
    fn run(self) {
        let mut buf = vec![0u8; 65_536];
        let mut out = Vec::with_capacity(64 * 1024);
        while !self.shared.stop.load(Ordering::Relaxed) {
            let Ok((n, from)) = self.socket.recv_from(&mut buf) else {
                continue;
            };
            let received = Instant::now();
            match decode_packet(&buf[..n]) {
                Ok(Packet::Connect(_) | Packet::Discovery(_)) => {
                    self.remember(from);
                    self.server_info(&mut out);
                }
                Ok(Packet::KeepAlive) => self.remember(from),
                Ok(Packet::RequestModelDef) => {
                    if encode_model_defs_into(&self.options.defs, self.options.version, &mut out)
                        .is_err()
                    {
                        continue;
                    }
                }
                Ok(Packet::EchoRequest(stamp)) => {
                    let ticks = received
                        .saturating_duration_since(self.options.epoch)
                        .as_micros() as u64;
                    let echo = EchoResponse {
                        request_stamp: stamp,
                        server_ticks: ticks,
                    };
                    encode_echo_response_into(&echo, &mut out);
                }
                Ok(Packet::Request(cmd)) if cmd.starts_with(b"FrameRate") => {
                    out.clear();
                    out.extend_from_slice(&(MessageId::Response as u16).to_le_bytes());
                    out.extend_from_slice(&4u16.to_le_bytes());
                    out.extend_from_slice(&self.options.rate_hz.to_le_bytes());
                }
                _ => continue,
            }
            let _ = self.socket.send_to(&out, from);
        }
    }

    fn remember(&self, client: SocketAddr) {
        if let Ok(mut c) = self.shared.clients.lock() {
            if !c.contains(&client) {
                c.push(client);
            }
        }
    }

    fn server_info(&self, out: &mut Vec<u8>) {
        let (multicast, group, port) = match self.options.multicast {
            Some(SocketAddr::V4(g)) => (true, g.ip().octets(), g.port()),
            _ => (false, [0; 4], 0),
        };
        let info = ServerInfo {
            app_name: "emoshift Motive stand-in".into(),
            app_version: [0, 1, 0, 0],
            natnet_version: self.options.version,
            connection: Some(ConnectionInfo {
                clock_frequency_hz: CLOCK_HZ,
                data_port: port,
                multicast,
                multicast_group: group,
            }),
        };
        let _ = encode_server_info_into(&info, out);
    }
}
