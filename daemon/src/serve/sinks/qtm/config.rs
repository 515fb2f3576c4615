//! The QTM server's settings: the `qtm_server*` keys of the config (and their flags), checked
//! once into a [`QtmServerConfig`].

use std::net::SocketAddr;

use protocol::qtm::{DEFAULT_PORT, DISCOVERY_PORT};

use crate::serve::config_error::{parse_addr, ConfigError};

/// The default address: QTM's little-endian RT port, loopback only.
pub const DEFAULT_QTM_SERVER: &str = "127.0.0.1:22223";
/// Clients served at most; connects beyond get QTM's error packet and are closed.
pub const DEFAULT_MAX_CLIENTS: usize = 16;

/// The `qtm_server*` keys as written.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RawQtmServer {
    /// `qtm_server`: the RT address, `IP[:PORT]`.
    pub server: Option<String>,
    /// `qtm_server_max_clients`: clients at most.
    pub max_clients: Option<usize>,
    /// `qtm_server_discovery`: where discovery requests are answered, `IP[:PORT]`, or `off`
    /// (default: the server's IP, port 22226).
    pub discovery: Option<String>,
}

/// A checked QTM server.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct QtmServerConfig {
    /// The RT (TCP) address.
    pub addr: SocketAddr,
    /// Clients at most.
    pub max_clients: usize,
    /// The discovery (UDP) address, when discovery is answered.
    pub discovery: Option<SocketAddr>,
}

impl RawQtmServer {
    /// `None` when no server is asked for (then the other `qtm_server*` keys must be absent).
    ///
    /// # Errors
    /// The first bad value, named by its key.
    pub fn validate(self) -> Result<Option<QtmServerConfig>, ConfigError> {
        let Some(server) = self.server else {
            if self.max_clients.is_some() || self.discovery.is_some() {
                return Err(ConfigError::Range {
                    key: "qtm_server",
                    value: "absent".into(),
                    range: "an IP[:PORT] when other qtm_server_* keys are set",
                });
            }
            return Ok(None);
        };
        let addr = parse_addr("qtm_server", &server, DEFAULT_PORT)?;
        let max_clients = self.max_clients.unwrap_or(DEFAULT_MAX_CLIENTS);
        if !(1..=256).contains(&max_clients) {
            return Err(ConfigError::Range {
                key: "qtm_server_max_clients",
                value: max_clients.to_string(),
                range: "1..=256",
            });
        }
        let discovery = match self.discovery.as_deref() {
            Some("off") => None,
            Some(d) => Some(parse_addr("qtm_server_discovery", d, DISCOVERY_PORT)?),
            None => Some(SocketAddr::new(addr.ip(), DISCOVERY_PORT)),
        };
        Ok(Some(QtmServerConfig {
            addr,
            max_clients,
            discovery,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_and_refusals() {
        let c = RawQtmServer {
            server: Some("127.0.0.1".into()),
            ..RawQtmServer::default()
        }
        .validate()
        .expect("valid")
        .expect("a server");
        assert_eq!(c.addr, "127.0.0.1:22223".parse().expect("addr"));
        assert_eq!(c.discovery, Some("127.0.0.1:22226".parse().expect("addr")));
        let off = RawQtmServer {
            server: Some("127.0.0.1:0".into()),
            discovery: Some("off".into()),
            ..RawQtmServer::default()
        };
        assert_eq!(
            off.validate().expect("valid").expect("server").discovery,
            None
        );
        let stray = RawQtmServer {
            max_clients: Some(3),
            ..RawQtmServer::default()
        };
        assert!(stray.validate().is_err());
        let zero = RawQtmServer {
            server: Some("127.0.0.1".into()),
            max_clients: Some(0),
            ..RawQtmServer::default()
        };
        assert!(zero.validate().is_err());
    }
}
