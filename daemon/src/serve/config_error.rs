//! Why a configuration is refused ([`ConfigError`]): one error for every part of the config
//! (the service's keys, a source's, the monitor's), each naming the key and the value. A leaf:
//! the parts that check keys import it, it imports none of them.

use std::net::{IpAddr, SocketAddr};

/// Why a configuration is refused; each names the key and the value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// The TOML does not parse, has an unknown key or a value of the wrong type.
    #[error("line {line}{}: {message}", key.as_ref().map(|k| format!(", key {k}")).unwrap_or_default())]
    Toml {
        /// 1-based line of the problem (0 when toml gives no place).
        line: usize,
        /// The key on that line, if it has one.
        key: Option<String>,
        /// What toml says.
        message: String,
    },
    /// An allow-list entry that is not a network.
    #[error("{key}: {message}")]
    Network {
        /// Key.
        key: &'static str,
        /// Why.
        message: String,
    },
    /// An address that does not parse.
    #[error("{key}: {value:?} is not an IP:PORT address")]
    Address {
        /// Key.
        key: &'static str,
        /// Value.
        value: String,
    },
    /// `send` with an unknown profile.
    #[error("send: {value:?}: unknown profile, expected compact, flat-split or components")]
    Profile {
        /// Value.
        value: String,
    },
    /// A number out of range.
    #[error("{key}: {value} is out of range ({range})")]
    Range {
        /// Key.
        key: &'static str,
        /// Value, printed.
        value: String,
        /// Accepted range.
        range: &'static str,
    },
    /// The frame and control sockets on one UDP port.
    #[error(
        "listen {listen} and control {control} share a port: the frame socket and the control \
         socket each need their own"
    )]
    SharedPort {
        /// The frame socket.
        listen: SocketAddr,
        /// The control socket.
        control: SocketAddr,
    },
}

/// A config value `IP` or `IP:PORT` (`port` when none is given), for the server outputs'
/// addresses; an error names `key`.
///
/// # Errors
/// [`ConfigError::Address`] when `text` is neither.
pub(crate) fn parse_addr(
    key: &'static str,
    text: &str,
    port: u16,
) -> Result<SocketAddr, ConfigError> {
    if let Ok(a) = text.parse::<SocketAddr>() {
        return Ok(a);
    }
    text.parse::<IpAddr>()
        .map(|ip| SocketAddr::new(ip, port))
        .map_err(|_| ConfigError::Address {
            key,
            value: text.to_string(),
        })
}
