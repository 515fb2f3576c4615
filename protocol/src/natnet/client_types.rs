//! The [`Client`](super::Client)'s configuration, inputs and outputs.

use std::time::Duration;

use super::command::ServerInfo;
use super::modeldef::ModelDefs;
use super::version::NatNetVersion;

/// Timing and identity of a [`Client`]. Defaults: NatNet 3.0 connect, 1 s for every retry and
/// period, 3 s of silence before a reconnect, clock estimate over the last 8 echoes.
///
/// [`Client`]: super::Client
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ClientConfig {
    /// Version announced in the connect; from 4.0 it also asks for that bitstream version.
    pub natnet_version: NatNetVersion,
    /// Connect is resent this often until a server info arrives.
    pub connect_interval: Duration,
    /// Keep-alive period (unicast servers drop silent clients).
    pub keepalive_interval: Duration,
    /// Echo request period, for the clock offset.
    pub echo_interval: Duration,
    /// Model definitions are re-requested this often until they arrive, and never more often.
    pub modeldef_retry: Duration,
    /// No frame or reply for this long: the server is gone, reconnect.
    pub silence_timeout: Duration,
    /// Echo samples the clock estimate picks its lowest round trip from.
    pub clock_window: usize,
}

impl Default for ClientConfig {
    fn default() -> Self {
        ClientConfig {
            natnet_version: NatNetVersion::V3_0,
            connect_interval: Duration::from_secs(1),
            keepalive_interval: Duration::from_secs(1),
            echo_interval: Duration::from_secs(1),
            modeldef_retry: Duration::from_secs(1),
            silence_timeout: Duration::from_secs(3),
            clock_window: 8,
        }
    }
}

/// Which socket a datagram came in on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Channel {
    /// The command socket (replies to what [`Client::poll_transmit`] sent).
    ///
    /// [`Client::poll_transmit`]: super::Client::poll_transmit
    Command,
    /// The data socket (frames; multicast or unicast).
    Data,
}

/// What [`Client::handle_datagram`] made of a datagram.
///
/// [`Client::handle_datagram`]: super::Client::handle_datagram
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Incoming {
    /// A NAT_FRAMEOFDATA: decode it with [`Client::frame_version`], then call
    /// [`Client::handle_frame`].
    ///
    /// [`Client::frame_version`]: super::Client::frame_version
    /// [`Client::handle_frame`]: super::Client::handle_frame
    Frame,
    /// A command message, handled (its effects come out of `poll_event`/`poll_transmit`).
    Handled,
    /// Valid, but nothing for this client (a request from another client, a frame before the
    /// server info, a command message on the data socket).
    Ignored,
}

/// Why the session lost its server.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DisconnectReason {
    /// Nothing heard for [`ClientConfig::silence_timeout`].
    Silent,
    /// A server info with another identity (Motive restarted, another version, another port).
    ServerChanged,
    /// The server sent NAT_DISCONNECT.
    ServerDisconnected,
    /// The server sent NAT_DISCONNECTBYTIMEOUT: it had dropped us.
    DroppedByServer,
}

/// The server clock relative to the local one, from the echo with the lowest round trip
/// (Cristian's algorithm, as NatNetLib does).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClockEstimate {
    /// Server clock (seconds: ticks / frequency) minus local time (seconds since the
    /// client's creation instant).
    pub offset_s: f64,
    /// Round trip of the echo the estimate comes from.
    pub rtt: Duration,
    /// Server ticks per second.
    pub clock_frequency_hz: u64,
}

impl ClockEstimate {
    /// Local time (since the client's creation) of a server high-resolution stamp, e.g. a
    /// frame's `camera_mid_exposure`. `None` if it falls before the creation instant.
    pub fn local_time_of(&self, server_ticks: u64) -> Option<Duration> {
        if self.clock_frequency_hz == 0 {
            return None;
        }
        let server_s = server_ticks as f64 / self.clock_frequency_hz as f64;
        Duration::try_from_secs_f64(server_s - self.offset_s).ok()
    }
}

/// What the session reports.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// A server answered (or answered again, changed): frames now decode with its version.
    Connected(ServerInfo),
    /// Model definitions arrived (after connect, or after the models changed).
    ModelDefs(ModelDefs),
    /// The server is gone or changed; the session reconnects by itself.
    Disconnected(DisconnectReason),
    /// The clock estimate changed.
    ClockOffset(ClockEstimate),
    /// A `Bitstream` reply switched the frame version.
    VersionChanged(NatNetVersion),
}
