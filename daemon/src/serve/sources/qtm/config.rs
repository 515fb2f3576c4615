//! The QTM source's settings: the `qtm*` keys of the config (and `--qtm`), checked once into a
//! [`QtmConfig`].

use std::collections::BTreeMap;
use std::net::{SocketAddr, ToSocketAddrs};

use protocol::qtm::DEFAULT_PORT;

use crate::serve::config_error::ConfigError;

/// The `qtm*` keys as written.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RawQtm {
    /// `qtm`: QTM's RT address, `HOST[:PORT]` (port 22223).
    pub server: Option<String>,
    /// `qtm_performers`: performer name to label pattern, `"Alice_*"`.
    pub performers: BTreeMap<String, String>,
}

/// A checked QTM source.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct QtmConfig {
    /// QTM's RT address.
    pub server: SocketAddr,
    /// Performers as (name, label prefix); empty: one stream of every label.
    pub performers: Vec<(String, String)>,
}

impl RawQtm {
    /// `None` when no QTM source is asked for.
    ///
    /// # Errors
    /// An address that does not resolve, a pattern that is not `PREFIX*`, performers without
    /// `qtm`.
    pub fn validate(self) -> Result<Option<QtmConfig>, ConfigError> {
        let Some(server) = self.server else {
            if !self.performers.is_empty() {
                return Err(ConfigError::Range {
                    key: "qtm",
                    value: "absent".into(),
                    range: "a HOST[:PORT] when qtm_performers is set",
                });
            }
            return Ok(None);
        };
        let with_port = if server.parse::<SocketAddr>().is_ok() || server.contains(':') {
            server.clone()
        } else {
            format!("{server}:{DEFAULT_PORT}")
        };
        let addr = with_port
            .to_socket_addrs()
            .ok()
            .and_then(|mut a| a.next())
            .ok_or(ConfigError::Address {
                key: "qtm",
                value: server,
            })?;
        let mut performers = Vec::with_capacity(self.performers.len());
        for (name, pattern) in self.performers {
            match pattern.strip_suffix('*') {
                Some(prefix) if !prefix.contains('*') && !name.is_empty() => {
                    performers.push((name, prefix.to_string()));
                }
                _ => {
                    return Err(ConfigError::Range {
                        key: "qtm_performers",
                        value: format!("{name} = {pattern:?}"),
                        range: "a label prefix ending in one *, e.g. alice = \"Alice_*\"",
                    })
                }
            }
        }
        Ok(Some(QtmConfig {
            server: addr,
            performers,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn port_defaults_and_patterns_are_checked() {
        let mut raw = RawQtm {
            server: Some("127.0.0.1".into()),
            ..RawQtm::default()
        };
        raw.performers.insert("alice".into(), "Alice_*".into());
        let c = raw.clone().validate().expect("valid").expect("a source");
        assert_eq!(c.server, "127.0.0.1:22223".parse().expect("addr"));
        assert_eq!(c.performers, vec![("alice".into(), "Alice_".into())]);
        raw.performers.insert("bob".into(), "Bob_".into());
        assert!(raw.validate().is_err(), "a pattern without * is refused");
        let mut stray = RawQtm::default();
        stray.performers.insert("a".into(), "A*".into());
        assert!(stray.validate().is_err());
    }
}
