//! The NatNet session with its sockets: protocol's sans-IO [`Client`] driven by a command
//! socket, a data socket and a timer. Each frame is decoded here with the [`Session`]'s layout
//! ([`NatNetFrames`]) and each markerset goes to the owner's sink as a
//! [`engine::SourceFrame`]; `serve` and `record` are the owners.
//!
//! - **Command socket**: bound on the interface that reaches the server (loopback for a
//!   loopback server), only datagrams from the server's host taken. Connect, model definitions,
//!   keep-alive and echo go out from here; in unicast, frames come back here too.
//! - **Data socket**: a multicast group joined on the interface (bound to the group, port
//!   shared with other clients on the host), or a local unicast address; from `natnet_data`,
//!   else what the server info announces. Rebound when a new server info says otherwise.
//! - **Server loss**: the client reconnects by itself; meanwhile frames that still come are
//!   decoded with the last session, so a restart costs only the frames sent while the server
//!   was down.

use std::net::{Ipv4Addr, SocketAddr};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use protocol::natnet::{
    check_packet, encode_request_into, Channel, Client, ClientConfig, ClockEstimate, Incoming,
    MessageId, ServerInfo,
};
use protocol::FrameBuf;
use tokio::net::UdpSocket;
use tokio_util::sync::CancellationToken;

mod events;

use super::config::NatNetConfig;
use super::frames::{LayoutIds, NatNetFrames, NatNetLayout};
use super::status::NatNetStatus;
use super::wire::{join_multicast, models_changed, recv};
use crate::serve::net::bind_receiver_std;
use crate::serve::sources::{Answer, Arrival, FrameSink, InputCounters};

/// How often the owner hears the status even when nothing happens.
const STATUS_EVERY: Duration = Duration::from_secs(1);
/// How often a frame is decoded here to look for assets the model definitions lack.
const FRAME_CHECK_EVERY: Duration = Duration::from_secs(1);

/// What frames of the current session are decoded with, and how its clock maps to ours.
#[derive(Debug, Clone)]
pub struct Session {
    /// The server's command address (the streams' source).
    pub server: SocketAddr,
    /// Version, clock rate, timecode rate, markersets.
    pub layout: NatNetLayout,
    /// The capture rate the server announced (its answer to `FrameRate`).
    pub announced_rate_hz: Option<f64>,
    /// The session's local epoch and the server clock estimate against it.
    clock: Option<(Instant, ClockEstimate)>,
}

impl Session {
    /// The local instant of a capture time in µs of the server's clock, once an echo came
    /// back.
    pub fn local_instant(&self, capture_us: i64) -> Option<Instant> {
        let (epoch, est) = self.clock?;
        let local_s = capture_us as f64 / 1e6 - est.offset_s;
        Some(epoch + Duration::try_from_secs_f64(local_s).ok()?)
    }
}

/// A NatNet source's sockets and session.
#[derive(Debug)]
pub struct Link {
    config: NatNetConfig,
    command: UdpSocket,
    data: Option<(SocketAddr, UdpSocket)>,
    client: Client,
    epoch: Instant,
    info: Option<ServerInfo>,
    session: Option<Session>,
    ids: LayoutIds,
    /// Frames decoded into markersets, reused.
    frames: NatNetFrames,
    /// One markerset's frame.
    buf: FrameBuf,
    counters: Arc<InputCounters>,
    /// When a frame is next decoded here (see [`FRAME_CHECK_EVERY`]).
    next_frame_check: Instant,
    status: NatNetStatus,
    /// `FrameRate` is to be asked (after a connect) / has been asked and not answered.
    rate: (bool, bool),
    announced_rate_hz: Option<f64>,
    /// Logs why a markerset's frames make no stream (a NatNet server cannot hear it), as the
    /// OSC frame socket logs and answers it.
    answer: Arc<Answer>,
}

impl Link {
    /// Binds the command socket (the data socket waits for the server info) and starts
    /// connecting; counts into `counters`.
    ///
    /// # Errors
    /// The command socket cannot be bound.
    pub fn open(config: NatNetConfig, counters: Arc<InputCounters>) -> Result<Link> {
        let local: SocketAddr = match config.server.ip().is_loopback() {
            true => (Ipv4Addr::LOCALHOST, 0).into(),
            false => (Ipv4Addr::UNSPECIFIED, 0).into(),
        };
        let command = bind_receiver_std(local).context("binding the NatNet command socket")?;
        command.set_nonblocking(true)?;
        let epoch = Instant::now();
        let status = NatNetStatus {
            server: config.server.to_string(),
            ..NatNetStatus::default()
        };
        let mut link = Link {
            command: UdpSocket::from_std(command)?,
            data: None,
            client: Client::new(ClientConfig::default(), epoch),
            epoch,
            info: None,
            session: None,
            ids: LayoutIds::default(),
            frames: NatNetFrames::new(protocol::MAX_FRAME_MARKERS),
            buf: FrameBuf::with_max_markers(protocol::MAX_FRAME_MARKERS),
            counters,
            next_frame_check: epoch,
            status,
            rate: (false, false),
            announced_rate_hz: None,
            answer: Arc::new(Answer::new(None)),
            config,
        };
        if let Some(addr) = link.config.data {
            link.bind_data(addr)?;
        }
        Ok(link)
    }

    /// Runs the session until `shutdown`: each markerset of every frame goes to `on_frame`
    /// with its arrival; `on_status` hears every change and once a second.
    ///
    /// # Errors
    /// None yet: a data socket that cannot be opened is logged and shown in the status.
    pub async fn run(
        mut self,
        shutdown: CancellationToken,
        on_frame: &mut FrameSink<'_>,
        on_status: &mut (dyn FnMut(&NatNetStatus) + Send),
    ) -> Result<()> {
        tracing::info!(target: "emoshift", server = %self.config.server, "natnet: connecting");
        let mut buf = vec![0u8; protocol::MAX_UDP_PAYLOAD + 1];
        let mut data_buf = vec![0u8; protocol::MAX_UDP_PAYLOAD + 1];
        let mut next_status = Instant::now();
        // One timer, moved only when the deadline moves: a frame's wake-up registers nothing.
        let timer = tokio::time::sleep_until(next_status.into());
        tokio::pin!(timer);
        loop {
            self.flush().await;
            if self.drain_events() || Instant::now() >= next_status {
                on_status(&self.status);
                next_status = Instant::now() + STATUS_EVERY;
            }
            let deadline = self
                .client
                .poll_timeout()
                .unwrap_or_else(|| Instant::now() + STATUS_EVERY)
                .min(next_status)
                // A deadline already past fires in a millisecond, never in a spin.
                .max(Instant::now() + Duration::from_millis(1));
            if timer.deadline() != deadline.into() {
                timer.as_mut().reset(deadline.into());
            }
            tokio::select! {
                () = shutdown.cancelled() => break,
                r = self.command.recv_from(&mut buf) => {
                    if let Ok((n, from)) = r {
                        // Unicast frames come from the server's data port, not its
                        // command port: any port of the server's host.
                        if from.ip() == self.config.server.ip() {
                            self.datagram(Channel::Command, &buf[..n], on_frame);
                        }
                    }
                }
                r = recv(self.data.as_ref().map(|d| &d.1), &mut data_buf) => {
                    if let Ok(n) = r {
                        self.datagram(Channel::Data, &data_buf[..n], on_frame);
                    }
                }
                () = &mut timer => {
                    self.client.handle_timeout(Instant::now());
                }
            }
        }
        on_status(&self.status);
        Ok(())
    }

    /// One datagram from the server.
    fn datagram(&mut self, channel: Channel, bytes: &[u8], on_frame: &mut FrameSink<'_>) {
        let now = Instant::now();
        if channel == Channel::Command && self.rate.1 {
            self.frame_rate_reply(bytes);
        }
        let incoming = match self.client.handle_datagram(now, channel, bytes) {
            Ok(i) => i,
            Err(e) => {
                self.status.bad_datagrams += 1;
                tracing::debug!(target: "emoshift", error = %e, "natnet: bad datagram");
                return;
            }
        };
        let is_frame = incoming == Incoming::Frame
            || (incoming == Incoming::Ignored && check_packet(bytes) == Ok(MessageId::FrameOfData));
        let Some(session) = self.session.as_ref().filter(|_| is_frame) else {
            tracing::trace!(target: "emoshift", ?incoming, session = self.session.is_some(),
                "natnet: datagram not handed on");
            return;
        };
        self.status.frames += 1;
        let layout = &session.layout;
        let counters = &self.counters;
        let answer = &self.answer;
        let decoded = self.frames.handle_datagram(
            session.server,
            bytes,
            layout,
            &mut self.buf,
            &mut |frame| {
                InputCounters::add(&counters.frames_in);
                let arrival = Arrival {
                    received: now,
                    captured: session.local_instant(frame.frame.header().capture_time_us),
                    answer: Some(Arc::clone(answer)),
                    announced_rate_hz: session.announced_rate_hz,
                };
                on_frame(frame, &arrival);
            },
        );
        if decoded.is_err() {
            InputCounters::add(&self.counters.bad_frames);
            return;
        }
        // The session needs a frame only to notice new models: at once when the frame says
        // they changed, else once a second (an asset the model definitions do not describe
        // yet).
        if incoming == Incoming::Frame && (models_changed(bytes) || now >= self.next_frame_check) {
            self.next_frame_check = now + FRAME_CHECK_EVERY;
            self.client.handle_frame(now, self.frames.frame());
        }
    }

    /// Sends what the client wants sent, and the `FrameRate` question after a connect.
    async fn flush(&mut self) {
        while let Some(bytes) = self.client.poll_transmit() {
            // A lost request is retried by the client's timers.
            let _ = self.command.send_to(bytes, self.config.server).await;
        }
        if std::mem::take(&mut self.rate.0) {
            let mut out = Vec::with_capacity(16);
            if encode_request_into("FrameRate", &mut out).is_ok() {
                let _ = self.command.send_to(&out, self.config.server).await;
                self.rate.1 = true;
            }
        }
    }

    /// Opens the data socket at `addr`: joins a multicast group, or binds a unicast address.
    fn bind_data(&mut self, addr: SocketAddr) -> Result<()> {
        let socket = match addr {
            SocketAddr::V4(v4) if v4.ip().is_multicast() => {
                let iface =
                    self.config
                        .interface
                        .unwrap_or(if self.config.server.ip().is_loopback() {
                            Ipv4Addr::LOCALHOST
                        } else {
                            Ipv4Addr::UNSPECIFIED
                        });
                join_multicast(addr, *v4.ip(), iface).with_context(|| {
                    format!("joining the NatNet multicast group {addr} on {iface}")
                })?
            }
            _ => bind_receiver_std(addr)
                .with_context(|| format!("binding the NatNet data socket {addr}"))?,
        };
        socket.set_nonblocking(true)?;
        self.data = Some((addr, UdpSocket::from_std(socket)?));
        Ok(())
    }
}
