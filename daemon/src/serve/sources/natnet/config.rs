//! The NatNet source's settings: the `natnet*` keys of the config (and their flags), checked
//! once into a [`NatNetConfig`].

use std::collections::HashMap;
use std::net::{IpAddr, SocketAddr};

use protocol::natnet::DEFAULT_COMMAND_PORT;
use protocol::TimecodeRate;

use super::frames::Naming;
use crate::serve::config_error::ConfigError;

/// The `natnet*` keys as written.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RawNatNet {
    /// `natnet`: the server's command channel, `IP[:PORT]` (port 1510 by default).
    pub server: Option<String>,
    /// `natnet_data`: where frames arrive, `IP:PORT`: a multicast group (joined on the
    /// interface) or a local unicast address; by default what the server info announces.
    pub data: Option<String>,
    /// `natnet_interface`: local IPv4 address multicast is joined on.
    pub interface: Option<String>,
    /// `natnet_timecode_rate`: the rate of Motive's timecode (`29.97df`, `30`, `25`...).
    pub timecode_rate: Option<String>,
    /// `natnet_names`: `asset:marker` (default), `asset_marker` or `marker`.
    pub names: Option<String>,
    /// `[natnet_rename]`: built names to model labels.
    pub rename: HashMap<String, String>,
}

/// A checked NatNet source.
#[derive(Debug, Clone, PartialEq)]
pub struct NatNetConfig {
    /// The server's command address.
    pub server: SocketAddr,
    /// Where frames arrive, if not where the server info says.
    pub data: Option<SocketAddr>,
    /// Interface multicast is joined on (by default loopback for a loopback server, else any).
    pub interface: Option<std::net::Ipv4Addr>,
    /// Timecode rate (NatNet does not send it).
    pub timecode_rate: Option<TimecodeRate>,
    /// How markers are named.
    pub naming: Naming,
}

impl RawNatNet {
    /// `None` when no server is given (then every other `natnet*` key must be absent too).
    ///
    /// # Errors
    /// The first bad value, named by its key.
    pub fn validate(self) -> Result<Option<NatNetConfig>, ConfigError> {
        let Some(server) = self.server else {
            let stray = self.data.is_some()
                || self.interface.is_some()
                || self.timecode_rate.is_some()
                || self.names.is_some()
                || !self.rename.is_empty();
            if stray {
                return Err(ConfigError::Range {
                    key: "natnet",
                    value: "absent".into(),
                    range: "a server IP[:PORT] when other natnet_* keys are set",
                });
            }
            return Ok(None);
        };
        let server = parse_server(&server)?;
        let data = self.data.map(|d| parse_key("natnet_data", d)).transpose()?;
        let interface = self
            .interface
            .map(|i| parse_key("natnet_interface", i))
            .transpose()?;
        let timecode_rate = self.timecode_rate.map(parse_rate).transpose()?;
        let separator = parse_names(self.names.as_deref().unwrap_or("asset:marker"))?;
        Ok(Some(NatNetConfig {
            server,
            data,
            interface,
            timecode_rate,
            naming: Naming {
                separator,
                rename: self.rename,
            },
        }))
    }
}

/// An address key's value.
fn parse_key<T: std::str::FromStr>(key: &'static str, value: String) -> Result<T, ConfigError> {
    value
        .parse()
        .map_err(|_| ConfigError::Address { key, value })
}

/// `natnet_timecode_rate`.
fn parse_rate(r: String) -> Result<TimecodeRate, ConfigError> {
    TimecodeRate::parse(&r).map_err(|e| ConfigError::Range {
        key: "natnet_timecode_rate",
        value: format!("{r:?} ({e})"),
        range: "24, 25, 29.97df, 30, 59.94df, 60 or N/D[df]",
    })
}

/// `natnet_names`: the separator between asset and marker names (`None`: bare markers).
fn parse_names(names: &str) -> Result<Option<String>, ConfigError> {
    match names {
        "asset:marker" => Ok(Some(":".to_string())),
        "asset_marker" => Ok(Some("_".to_string())),
        "marker" => Ok(None),
        other => Err(ConfigError::Range {
            key: "natnet_names",
            value: format!("{other:?}"),
            range: "asset:marker, asset_marker or marker",
        }),
    }
}

/// `IP` or `IP:PORT` (IPv6 as `[::1]:PORT`).
fn parse_server(text: &str) -> Result<SocketAddr, ConfigError> {
    if let Ok(a) = text.parse::<SocketAddr>() {
        return Ok(a);
    }
    text.parse::<IpAddr>()
        .map(|ip| SocketAddr::new(ip, DEFAULT_COMMAND_PORT))
        .map_err(|_| ConfigError::Address {
            key: "natnet",
            value: text.to_string(),
        })
}

#[cfg(test)]
mod tests;
