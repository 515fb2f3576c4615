//! A sans-IO NatNet client session: connect, model definitions, keep-alive, clock offset,
//! reconnection. The caller owns the sockets and the clock.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

pub use super::client_types::{
    Channel, ClientConfig, ClockEstimate, DisconnectReason, Event, Incoming,
};
use super::command::{
    decode_packet, encode_connect_into, encode_echo_request_into, response_text, Connect,
    EchoResponse, Packet, ServerInfo,
};
use super::error::{ModelDefError, NatNetError};
use super::frame::FrameOfData;
use super::message::{encode_empty_into, MessageId};
use super::modeldef::decode_model_defs;
use super::version::{parse_bitstream_reply, NatNetVersion};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Request {
    Connect,
    ModelDef,
    KeepAlive,
    Echo(u64),
}

/// A NatNet client session, sans IO, in the style of quinn-proto's `Connection`.
///
/// Call order, all with the caller's clock:
/// 1. [`Client::new`] queues the first connect.
/// 2. Send everything [`Client::poll_transmit`] yields to the server's command port.
/// 3. Feed every datagram from the server with [`Client::handle_datagram`] (drop other
///    senders first: this type knows no addresses). For [`Incoming::Frame`], decode it with
///    [`decode_frame_into`](super::decode_frame_into) and [`Client::frame_version`], then
///    pass the frame to [`Client::handle_frame`] (model changes, unknown markersets).
/// 4. Drain [`Client::poll_event`].
/// 5. Arm a timer for [`Client::poll_timeout`]; when it fires call [`Client::handle_timeout`].
/// 6. Repeat from 2. `handle_*` never sends: outputs wait in the queues until polled.
#[derive(Debug)]
pub struct Client {
    config: ClientConfig,
    epoch: Instant,
    server: Option<ServerInfo>,
    version: Option<NatNetVersion>,
    markersets: Vec<String>,
    modeldefs_pending: bool,
    last_modeldef_request: Option<Instant>,
    next_connect: Instant,
    next_keepalive: Instant,
    next_echo: Instant,
    last_heard: Instant,
    echoes: VecDeque<(Duration, f64)>,
    clock: Option<ClockEstimate>,
    transmits: VecDeque<Request>,
    tx: Vec<u8>,
    events: VecDeque<Event>,
}

impl Client {
    /// A session that starts connecting at `now` (also its local clock's epoch).
    pub fn new(config: ClientConfig, now: Instant) -> Self {
        let mut c = Client {
            epoch: now,
            server: None,
            version: None,
            markersets: Vec::new(),
            modeldefs_pending: false,
            last_modeldef_request: None,
            next_connect: now + config.connect_interval,
            next_keepalive: now,
            next_echo: now,
            last_heard: now,
            echoes: VecDeque::with_capacity(config.clock_window.max(1)),
            clock: None,
            transmits: VecDeque::with_capacity(8),
            tx: Vec::with_capacity(300),
            events: VecDeque::with_capacity(8),
            config,
        };
        c.transmits.push_back(Request::Connect);
        c
    }

    /// The server this session is connected to.
    pub fn server(&self) -> Option<&ServerInfo> {
        self.server.as_ref()
    }

    /// The version frames and model definitions are currently sent in, once connected.
    pub fn frame_version(&self) -> Option<NatNetVersion> {
        self.version
    }

    /// The current clock estimate, once an echo came back.
    pub fn clock(&self) -> Option<ClockEstimate> {
        self.clock
    }

    /// Local instant of a server high-resolution stamp (see [`ClockEstimate::local_time_of`]).
    pub fn server_ticks_to_instant(&self, server_ticks: u64) -> Option<Instant> {
        Some(self.epoch + self.clock?.local_time_of(server_ticks)?)
    }

    /// Takes one datagram from the server.
    ///
    /// # Errors
    ///
    /// A malformed datagram, a model definition that does not decode, or a server info with
    /// an unsupported NatNet version (the session keeps trying to connect). Nothing changes.
    pub fn handle_datagram(
        &mut self,
        now: Instant,
        channel: Channel,
        bytes: &[u8],
    ) -> Result<Incoming, NatNetError> {
        let packet = decode_packet(bytes)?;
        if matches!(packet, Packet::FrameOfData) {
            self.last_heard = now;
            return Ok(if self.version.is_some() {
                Incoming::Frame
            } else {
                Incoming::Ignored
            });
        }
        if channel == Channel::Data {
            return Ok(Incoming::Ignored);
        }
        match packet {
            Packet::ServerInfo(info) => self.on_server_info(now, info)?,
            Packet::ModelDef => self.on_model_defs(now, bytes)?,
            Packet::EchoResponse(e) => self.on_echo(now, e),
            Packet::Response(payload) => self.on_response(now, payload),
            Packet::Disconnect => self.disconnect(now, DisconnectReason::ServerDisconnected),
            Packet::DisconnectByTimeout => self.disconnect(now, DisconnectReason::DroppedByServer),
            Packet::MessageString(_) | Packet::UnrecognizedRequest => self.last_heard = now,
            _ => return Ok(Incoming::Ignored),
        }
        Ok(Incoming::Handled)
    }

    /// Takes a frame decoded from a datagram [`Client::handle_datagram`] called a frame:
    /// re-requests model definitions when the frame says the models changed or carries a
    /// markerset they do not describe. Allocates nothing.
    pub fn handle_frame(&mut self, now: Instant, frame: &FrameOfData) {
        self.last_heard = now;
        if self.server.is_none() {
            return;
        }
        let unknown = !self.modeldefs_pending
            && frame
                .markersets()
                .any(|m| !self.markersets.iter().any(|n| n == m.name));
        if frame.params.tracked_models_changed() || unknown {
            self.request_modeldefs(now);
        }
    }

    /// Fires due timers: connect retries, keep-alive, echo, model definition retries, the
    /// silence timeout.
    pub fn handle_timeout(&mut self, now: Instant) {
        if self.server.is_none() {
            if now >= self.next_connect {
                self.transmits.push_back(Request::Connect);
                self.next_connect = now + self.config.connect_interval;
            }
            return;
        }
        if now.saturating_duration_since(self.last_heard) >= self.config.silence_timeout {
            self.disconnect(now, DisconnectReason::Silent);
            return;
        }
        if now >= self.next_keepalive {
            self.transmits.push_back(Request::KeepAlive);
            self.next_keepalive = now + self.config.keepalive_interval;
        }
        if now >= self.next_echo {
            let stamp = u64::try_from(now.saturating_duration_since(self.epoch).as_nanos())
                .unwrap_or(u64::MAX);
            self.transmits.push_back(Request::Echo(stamp));
            self.next_echo = now + self.config.echo_interval;
        }
        if self.modeldefs_pending && self.modeldef_due(now) {
            self.request_modeldefs(now);
        }
    }

    /// When [`Client::handle_timeout`] should next be called.
    pub fn poll_timeout(&self) -> Option<Instant> {
        if self.server.is_none() {
            return Some(self.next_connect);
        }
        let mut t = (self.last_heard + self.config.silence_timeout)
            .min(self.next_keepalive)
            .min(self.next_echo);
        if let (true, Some(last)) = (self.modeldefs_pending, self.last_modeldef_request) {
            t = t.min(last + self.config.modeldef_retry);
        }
        Some(t)
    }

    /// The next datagram for the server's command port. The bytes live until the next call.
    pub fn poll_transmit(&mut self) -> Option<&[u8]> {
        let req = self.transmits.pop_front()?;
        match req {
            Request::Connect => {
                let c = Connect::emoshift(self.config.natnet_version);
                encode_connect_into(&c, false, &mut self.tx)
                    .expect("emoshift's connect has a short NUL-free name");
            }
            Request::ModelDef => encode_empty_into(MessageId::RequestModelDef, &mut self.tx),
            Request::KeepAlive => encode_empty_into(MessageId::KeepAlive, &mut self.tx),
            Request::Echo(stamp) => encode_echo_request_into(stamp, &mut self.tx),
        }
        Some(&self.tx)
    }

    /// The next event.
    pub fn poll_event(&mut self) -> Option<Event> {
        self.events.pop_front()
    }

    fn on_server_info(&mut self, now: Instant, info: ServerInfo) -> Result<(), NatNetError> {
        info.natnet_version.check()?;
        self.last_heard = now;
        if self.server.as_ref() == Some(&info) {
            return Ok(());
        }
        if self.server.is_some() {
            self.disconnect(now, DisconnectReason::ServerChanged);
            self.transmits.clear();
        }
        self.version = Some(info.natnet_version);
        self.server = Some(info.clone());
        self.events.push_back(Event::Connected(info));
        self.next_keepalive = now;
        self.next_echo = now;
        self.last_modeldef_request = None;
        self.request_modeldefs(now);
        Ok(())
    }

    fn on_model_defs(&mut self, now: Instant, bytes: &[u8]) -> Result<(), NatNetError> {
        let Some(version) = self.version else {
            return Ok(());
        };
        let defs = decode_model_defs(bytes, version).map_err(|e| match e {
            ModelDefError::Packet(e) | ModelDefError::Description { source: e, .. } => e,
        })?;
        self.last_heard = now;
        self.markersets = defs.markersets.iter().map(|m| m.name.clone()).collect();
        self.modeldefs_pending = false;
        self.events.push_back(Event::ModelDefs(defs));
        Ok(())
    }

    fn on_echo(&mut self, now: Instant, e: EchoResponse) {
        self.last_heard = now;
        let Some(hz) = self
            .server
            .as_ref()
            .and_then(|s| s.connection)
            .map(|c| c.clock_frequency_hz)
        else {
            return;
        };
        let received = now.saturating_duration_since(self.epoch);
        let sent = Duration::from_nanos(e.request_stamp);
        if hz == 0 || sent > received {
            return;
        }
        let rtt = received - sent;
        let local_mid = (sent + rtt / 2).as_secs_f64();
        let offset = e.server_ticks as f64 / hz as f64 - local_mid;
        if self.echoes.len() >= self.config.clock_window.max(1) {
            self.echoes.pop_front();
        }
        self.echoes.push_back((rtt, offset));
        let best = self.echoes.iter().copied().min_by_key(|s| s.0);
        if let Some((rtt, offset_s)) = best {
            let est = ClockEstimate {
                offset_s,
                rtt,
                clock_frequency_hz: hz,
            };
            if self.clock != Some(est) {
                self.clock = Some(est);
                self.events.push_back(Event::ClockOffset(est));
            }
        }
    }

    fn on_response(&mut self, now: Instant, payload: &[u8]) {
        self.last_heard = now;
        let Some(v) = response_text(payload).and_then(parse_bitstream_reply) else {
            return;
        };
        if v.is_supported() && self.version.is_some() && self.version != Some(v) {
            self.version = Some(v);
            self.events.push_back(Event::VersionChanged(v));
        }
    }

    fn modeldef_due(&self, now: Instant) -> bool {
        self.last_modeldef_request
            .is_none_or(|t| now.saturating_duration_since(t) >= self.config.modeldef_retry)
    }

    fn request_modeldefs(&mut self, now: Instant) {
        self.modeldefs_pending = true;
        if self.modeldef_due(now) {
            self.transmits.push_back(Request::ModelDef);
            self.last_modeldef_request = Some(now);
        }
    }

    fn disconnect(&mut self, now: Instant, reason: DisconnectReason) {
        self.server = None;
        self.version = None;
        self.markersets.clear();
        self.modeldefs_pending = false;
        self.echoes.clear();
        self.clock = None;
        self.events.push_back(Event::Disconnected(reason));
        self.transmits.retain(|r| *r == Request::Connect);
        if self.transmits.is_empty() {
            self.transmits.push_back(Request::Connect);
        }
        self.next_connect = now + self.config.connect_interval;
        self.last_heard = now;
    }
}
