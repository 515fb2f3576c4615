//! The NatNet server's command channel, sans-IO: who may connect, what each client is
//! answered, which clients get frames and in which bitstream. The command task
//! ([`super::Commands::run`]) owns the socket and the clock; the processing thread's sink reads
//! the client table through the same lock.
//!
//! Call order: [`Session::handle_command`] per datagram (it writes the reply, if any, into the
//! caller's buffer), [`Session::poll_expired`] now and then; the sink, per frame,
//! [`Session::multicast`] or the [`Session::clients`] and [`Session::handle_send`] per send.
//!
//! Bad input and amplification:
//! - a peer outside the allow-list gets nothing (counted);
//! - an oversized, malformed or server-only message is counted and dropped; an unknown
//!   request gets Motive's NAT_UNRECOGNIZED_REQUEST;
//! - every reply is paid from a byte budget ([`super::counters::REPLY_BYTES_PER_S`],
//!   burst [`super::counters::REPLY_BURST_BYTES`]), so no flood of small requests turns into a flood of large replies;
//! - a connect is answered, but frames flow to a unicast client only once it sends a
//!   keep-alive, and stop when its keep-alives stop for a lease;
//! - the client table holds [`super::NatNetServerConfig::max_clients`] clients and as many
//!   connects waiting for their first keep-alive (the oldest waiting one makes room).

use std::net::{SocketAddr, SocketAddrV4};
use std::time::{Duration, Instant};

use engine::subscribers::{SendOutcome, Subscriber, Subscribers};
use protocol::natnet::{
    decode_command, encode_echo_response_into, encode_model_defs_into, encode_response_code_into,
    encode_response_f32_into, encode_server_info_into, encode_text_into, encode_unrecognized_into,
    Command, ConnectionInfo, EchoResponse, Hello, MessageId, ModelDefs, NatNetVersion, Request,
    ServerInfo, MAX_COMMAND_LEN,
};

use super::counters::{Budget, ServerCounters};
use crate::serve::allow::AllowList;

/// The server clock's rate: ticks are microseconds.
pub const CLOCK_HZ: u64 = 1_000_000;
/// How long a unicast client is served after its last keep-alive (NatNetLib sends one a
/// second or more often).
pub const LEASE: Duration = Duration::from_secs(10);
/// How long a connect waits for its first keep-alive.
pub const PENDING_FOR: Duration = Duration::from_secs(10);

/// A connect waiting for its first keep-alive.
#[derive(Debug, Clone, Copy)]
struct Pending {
    addr: SocketAddr,
    version: NatNetVersion,
    since: Instant,
}

/// What the server is, as its server info says.
#[derive(Debug, Clone)]
pub struct Identity {
    /// The application version announced (emoshift's).
    pub app_version: [u8; 4],
    /// The port frames come from (unicast).
    pub data_port: u16,
    /// The group frames go to, when multicast.
    pub multicast: Option<SocketAddrV4>,
    /// The bitstream of frames by default, and of the group's.
    pub version: NatNetVersion,
}

/// The command channel's state. See the module docs.
#[derive(Debug)]
pub struct Session {
    identity: Identity,
    allow: AllowList,
    clients: Subscribers<NatNetVersion>,
    pending: Vec<Pending>,
    max_clients: usize,
    budget: Budget,
    /// The model definitions clients are sent (the sink keeps them current).
    pub defs: ModelDefs,
    /// The capture rate `FrameRate` answers (0 until a stream is seen).
    pub rate_hz: f32,
    /// Counters since the start.
    pub counters: ServerCounters,
}

impl Session {
    /// A server that is `identity`, answering peers in `allow`, serving `max_clients`.
    pub fn new(identity: Identity, allow: AllowList, max_clients: usize) -> Session {
        Session {
            identity,
            allow,
            clients: Subscribers::new(&[], max_clients, 8, LEASE),
            pending: Vec::with_capacity(max_clients),
            max_clients,
            budget: Budget::default(),
            defs: ModelDefs::default(),
            rate_hz: 0.0,
            counters: ServerCounters::default(),
        }
    }

    /// The group frames go to, with its bitstream, when multicast.
    pub fn multicast(&self) -> Option<(SocketAddrV4, NatNetVersion)> {
        self.identity.multicast.map(|g| (g, self.identity.version))
    }

    /// The unicast clients that get frames, each with its bitstream.
    pub fn clients(&self) -> impl Iterator<Item = &Subscriber<NatNetVersion>> {
        self.clients.iter()
    }

    /// Unicast client `i`.
    pub fn client(&self, i: usize) -> Option<&Subscriber<NatNetVersion>> {
        self.clients.get(i)
    }

    /// Unicast clients that get frames.
    pub fn client_count(&self) -> usize {
        self.clients.len()
    }

    /// Connects still waiting for their first keep-alive.
    pub fn pending(&self) -> usize {
        self.pending.len()
    }

    /// Records a frame sent to client `i` (`bytes` long, or failed).
    pub fn handle_send(&mut self, i: usize, sent: Option<usize>, now: Instant) {
        self.count_sent(sent);
        if self.clients.handle_send(i, sent.is_some(), now) == SendOutcome::Dropped {
            tracing::info!(target: "emoshift", "natnet_server: a client dropped after repeated send failures");
        }
    }

    /// Records a frame sent to the group.
    pub fn handle_multicast(&mut self, sent: Option<usize>) {
        self.count_sent(sent);
    }

    /// A frame's send in the counters: `Some(0)` a full send buffer, `None` a send error.
    fn count_sent(&mut self, sent: Option<usize>) {
        match sent {
            Some(0) => self.counters.dropped_send_buffer += 1,
            Some(n) => {
                self.counters.frames_sent += 1;
                self.counters.bytes_sent += n as u64;
            }
            None => self.counters.send_errors += 1,
        }
    }

    /// Forgets clients whose keep-alives stopped and connects that never sent one.
    pub fn poll_expired(&mut self, now: Instant) {
        let gone = self.clients.poll_expired(now);
        self.counters.expired += gone.len() as u64;
        for addr in gone {
            tracing::info!(target: "emoshift", %addr, "natnet_server: client's lease ended (no keep-alive)");
        }
        self.pending
            .retain(|p| now.saturating_duration_since(p.since) < PENDING_FOR);
    }

    /// Handles one datagram from `peer` at `now` (`ticks`: the server clock then). Returns
    /// whether `out` holds a reply for `peer`.
    pub fn handle_command(
        &mut self,
        now: Instant,
        ticks: u64,
        (peer, datagram): (SocketAddr, &[u8]),
        out: &mut Vec<u8>,
    ) -> bool {
        out.clear();
        if !self.allow.allows(peer.ip()) {
            self.counters.not_allowed += 1;
            return false;
        }
        if datagram.len() > MAX_COMMAND_LEN {
            self.counters.oversized += 1;
            return false;
        }
        let command = match decode_command(datagram) {
            Ok(c) => c,
            Err(protocol::natnet::NatNetError::UnknownMessage { .. }) => {
                self.counters.malformed += 1;
                self.unrecognized(out);
                return self.pay(now, out);
            }
            Err(_) => {
                self.counters.malformed += 1;
                return false;
            }
        };
        self.answer(now, ticks, peer, command, out);
        !out.is_empty() && self.pay(now, out)
    }

    /// Pays for the reply in `out`, or clears it.
    fn pay(&mut self, now: Instant, out: &mut Vec<u8>) -> bool {
        if self.budget.take(now, out.len()) {
            return true;
        }
        self.counters.over_budget += 1;
        out.clear();
        false
    }

    fn answer(
        &mut self,
        now: Instant,
        ticks: u64,
        peer: SocketAddr,
        c: Command<'_>,
        out: &mut Vec<u8>,
    ) {
        match c {
            Command::Connect(hello) => {
                self.counters.connects += 1;
                let version = self.version_for(hello);
                if self.identity.multicast.is_none() {
                    self.remember(now, peer, version);
                }
                self.server_info(version, out);
            }
            Command::Discovery(hello) => {
                self.counters.connects += 1;
                self.server_info(self.version_for(hello), out);
            }
            Command::KeepAlive => self.keep_alive(now, peer),
            Command::RequestModelDef => {
                let version = self.version_of(peer);
                if encode_model_defs_into(&self.defs, version, out).is_ok() {
                    self.counters.modeldefs += 1;
                } else {
                    self.counters.encode_errors += 1;
                    out.clear();
                }
            }
            Command::EchoRequest(stamp) => {
                self.counters.echoes += 1;
                let echo = EchoResponse {
                    request_stamp: stamp,
                    server_ticks: ticks,
                };
                encode_echo_response_into(&echo, out);
            }
            Command::Request(r) => self.request(now, peer, r, out),
            Command::Disconnect => {
                self.counters.disconnects += 1;
                self.pending.retain(|p| p.addr != peer);
                let _ = self.clients.unsubscribe(peer);
            }
            Command::RequestFrameOfData => {
                // Motive sends the current frame; frames reach a client by its session here.
                self.counters.unknown_requests += 1;
                self.unrecognized(out);
            }
            Command::NotACommand(_) => self.counters.not_commands += 1,
        }
    }

    fn request(&mut self, now: Instant, peer: SocketAddr, r: Request<'_>, out: &mut Vec<u8>) {
        self.counters.requests += 1;
        match r {
            Request::Bitstream(Some(v)) if v.is_supported() => {
                self.set_version(now, peer, v);
                let text = format!("Bitstream,{}.{}", v.major, v.minor);
                let _ = encode_text_into(MessageId::Response, &text, out);
            }
            Request::Bitstream(_) => encode_response_code_into(1, out),
            Request::FrameRate => encode_response_f32_into(self.rate_hz, out),
            Request::UnitsToMillimeters => encode_response_f32_into(1000.0, out),
            Request::TimelinePlay | Request::TimelineStop => encode_response_code_into(0, out),
            Request::Other(_) => {
                self.counters.unknown_requests += 1;
                self.unrecognized(out);
            }
        }
    }

    /// The bitstream a connecting client gets: the group's when multicast; else the one a
    /// NatNet 4 client asks for, 3.1 for a NatNet 3 client, the server's otherwise.
    fn version_for(&self, hello: Hello) -> NatNetVersion {
        if self.identity.multicast.is_some() {
            return self.identity.version;
        }
        match (hello.bitstream, hello.natnet_version) {
            (Some(b), _) if b.is_supported() => b,
            (_, Some(v)) if v.major == 3 => NatNetVersion::V3_1,
            _ => self.identity.version,
        }
    }

    /// The bitstream `peer` gets now.
    fn version_of(&self, peer: SocketAddr) -> NatNetVersion {
        if let Some(s) = self.clients.iter().find(|s| s.addr == peer) {
            return s.wants;
        }
        match self.pending.iter().find(|p| p.addr == peer) {
            Some(p) => p.version,
            None => self.identity.version,
        }
    }

    /// A `Bitstream` request: this client's frames from now on (the group's, when
    /// multicast, as Motive switches its whole stream).
    fn set_version(&mut self, now: Instant, peer: SocketAddr, v: NatNetVersion) {
        if self.identity.multicast.is_some() {
            self.identity.version = v;
            return;
        }
        if let Some(p) = self.pending.iter_mut().find(|p| p.addr == peer) {
            p.version = v;
        }
        if self.clients.iter().any(|s| s.addr == peer) {
            let _ = self.clients.subscribe(now, peer, v, None);
        }
    }

    /// A unicast connect: the client waits for its first keep-alive (a renewal when it is
    /// already served).
    fn remember(&mut self, now: Instant, peer: SocketAddr, version: NatNetVersion) {
        if self.clients.iter().any(|s| s.addr == peer) {
            let _ = self.clients.subscribe(now, peer, version, None);
            return;
        }
        self.pending.retain(|p| p.addr != peer);
        if self.pending.len() >= self.max_clients {
            self.pending.remove(0);
        }
        self.pending.push(Pending {
            addr: peer,
            version,
            since: now,
        });
    }

    fn keep_alive(&mut self, now: Instant, peer: SocketAddr) {
        self.counters.keepalives += 1;
        let version = match self.pending.iter().position(|p| p.addr == peer) {
            Some(i) => self.pending[i].version,
            None => match self.clients.iter().find(|s| s.addr == peer) {
                Some(s) => s.wants,
                None => {
                    self.counters.keepalives_unknown += 1;
                    return;
                }
            },
        };
        match self.clients.subscribe(now, peer, version, None) {
            Ok(engine::subscribers::Change::Added(addr)) => {
                self.pending.retain(|p| p.addr != peer);
                tracing::info!(target: "emoshift", %addr, %version, "natnet_server: client connected");
            }
            Ok(_) => {}
            Err(_) => self.counters.clients_full += 1,
        }
    }

    fn info(&self, version: NatNetVersion) -> ServerInfo {
        let (multicast, group, port) = match self.identity.multicast {
            Some(g) => (true, g.ip().octets(), g.port()),
            None => (false, [0; 4], self.identity.data_port),
        };
        ServerInfo {
            app_name: "emoshift".into(),
            app_version: self.identity.app_version,
            natnet_version: version,
            connection: Some(ConnectionInfo {
                clock_frequency_hz: CLOCK_HZ,
                data_port: port,
                multicast,
                multicast_group: group,
            }),
        }
    }

    fn server_info(&self, version: NatNetVersion, out: &mut Vec<u8>) {
        if encode_server_info_into(&self.info(version), out).is_err() {
            out.clear();
        }
    }

    fn unrecognized(&self, out: &mut Vec<u8>) {
        if encode_unrecognized_into(&self.info(self.identity.version), out).is_err() {
            out.clear();
        }
    }
}

#[cfg(test)]
mod tests;
