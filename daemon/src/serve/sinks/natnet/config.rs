//! The NatNet server's settings: the `natnet_server*` keys of the config (and their flags),
//! checked once into a [`NatNetServerConfig`].

use std::net::{IpAddr, Ipv4Addr, SocketAddr, SocketAddrV4};

use protocol::natnet::{NatNetVersion, DEFAULT_COMMAND_PORT, DEFAULT_MULTICAST_GROUP};

use crate::serve::config_error::{parse_addr, ConfigError};

/// The default command address: Motive's port, loopback only.
pub const DEFAULT_NATNET_SERVER: &str = "127.0.0.1:1510";
/// Unicast clients served at most (each gets every frame); connects beyond wait their turn.
pub const DEFAULT_MAX_CLIENTS: usize = 16;

/// The `natnet_server*` keys as written.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RawNatNetServer {
    /// `natnet_server`: the command address, `IP[:PORT]` (data port = PORT + 1).
    pub server: Option<String>,
    /// `natnet_server_multicast`: stream to this group, `GROUP[:PORT]` (port: the data port).
    pub multicast: Option<String>,
    /// `natnet_server_interface`: local IPv4 address multicast goes out on.
    pub interface: Option<String>,
    /// `natnet_server_version`: the bitstream streamed unless a client asks for another.
    pub version: Option<String>,
    /// `natnet_server_raw`: a `<name>_raw` markerset with the unedited input too.
    pub raw: Option<bool>,
    /// `natnet_server_max_clients`: unicast clients at most.
    pub max_clients: Option<usize>,
}

/// A checked NatNet server.
#[derive(Debug, Clone, PartialEq)]
pub struct NatNetServerConfig {
    /// The command address; frames go out from PORT + 1 (any free port when PORT is 0).
    pub command: SocketAddr,
    /// The multicast group and port, when frames are multicast.
    pub multicast: Option<SocketAddrV4>,
    /// The interface multicast goes out on.
    pub interface: Ipv4Addr,
    /// The bitstream streamed by default (and to the group).
    pub version: NatNetVersion,
    /// Whether each performer's unedited input goes out as `<name>_raw` too.
    pub raw: bool,
    /// Unicast clients at most.
    pub max_clients: usize,
}

impl NatNetServerConfig {
    /// The data port: PORT + 1, like Motive's 1510/1511 (0 when the command port is 0).
    pub fn data_addr(&self) -> SocketAddr {
        let port = match self.command.port() {
            0 => 0,
            p => p.wrapping_add(1),
        };
        SocketAddr::new(self.command.ip(), port)
    }
}

impl RawNatNetServer {
    /// `None` when no server is asked for (then every other `natnet_server*` key must be
    /// absent too).
    ///
    /// # Errors
    /// The first bad value, named by its key.
    pub fn validate(self) -> Result<Option<NatNetServerConfig>, ConfigError> {
        let Some(server) = self.server else {
            let stray = self.multicast.is_some()
                || self.interface.is_some()
                || self.version.is_some()
                || self.raw.is_some()
                || self.max_clients.is_some();
            if stray {
                return Err(ConfigError::Range {
                    key: "natnet_server",
                    value: "absent".into(),
                    range: "an IP[:PORT] when other natnet_server_* keys are set",
                });
            }
            return Ok(None);
        };
        let command = parse_addr("natnet_server", &server, DEFAULT_COMMAND_PORT)?;
        if command.port() == u16::MAX {
            return Err(ConfigError::Range {
                key: "natnet_server",
                value: server,
                range: "a port below 65535 (the data port is the next one)",
            });
        }
        let interface = match self.interface {
            Some(i) => i.parse().map_err(|_| ConfigError::Address {
                key: "natnet_server_interface",
                value: i,
            })?,
            None => match command.ip() {
                IpAddr::V4(ip) => ip,
                IpAddr::V6(_) => Ipv4Addr::UNSPECIFIED,
            },
        };
        let data_port = match command.port() {
            0 => DEFAULT_COMMAND_PORT + 1,
            p => p + 1,
        };
        let multicast = self
            .multicast
            .map(|m| parse_group(&m, data_port))
            .transpose()?;
        let version = self.version.as_deref().map(parse_version).transpose()?;
        let max_clients = self.max_clients.unwrap_or(DEFAULT_MAX_CLIENTS);
        if !(1..=256).contains(&max_clients) {
            return Err(ConfigError::Range {
                key: "natnet_server_max_clients",
                value: max_clients.to_string(),
                range: "1..=256",
            });
        }
        Ok(Some(NatNetServerConfig {
            command,
            multicast,
            interface,
            version: version.unwrap_or(NatNetVersion::V4_1),
            raw: self.raw.unwrap_or(false),
            max_clients,
        }))
    }
}

/// `GROUP[:PORT]`, an IPv4 multicast group (an empty text: Motive's default group).
fn parse_group(text: &str, port: u16) -> Result<SocketAddrV4, ConfigError> {
    let text = if text.is_empty() {
        Ipv4Addr::from(DEFAULT_MULTICAST_GROUP).to_string()
    } else {
        text.to_string()
    };
    match parse_addr("natnet_server_multicast", &text, port)? {
        SocketAddr::V4(a) if a.ip().is_multicast() => Ok(a),
        _ => Err(ConfigError::Range {
            key: "natnet_server_multicast",
            value: text,
            range: "an IPv4 multicast group, e.g. 239.255.42.99[:1511]",
        }),
    }
}

/// `3.1`, `4.1` (any 3.x or 4.x).
fn parse_version(text: &str) -> Result<NatNetVersion, ConfigError> {
    let bad = || ConfigError::Range {
        key: "natnet_server_version",
        value: format!("{text:?}"),
        range: "a NatNet version 3.x or 4.x, e.g. 3.1 or 4.1",
    };
    let (major, minor) = text.trim().split_once('.').ok_or_else(bad)?;
    let v = NatNetVersion::new(
        major.parse().map_err(|_| bad())?,
        minor.parse().map_err(|_| bad())?,
        0,
        0,
    );
    if v.is_supported() {
        Ok(v)
    } else {
        Err(bad())
    }
}

#[cfg(test)]
mod tests;
