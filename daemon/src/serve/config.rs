//! Configuration of `emoshift serve`, in two stages: [`RawConfig`] (TOML, every key optional,
//! unknown keys rejected by name) with CLI flags laid over it, then one [`RawConfig::validate`]
//! into a [`Config`]. Defaults bind loopback only.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use protocol::Profile;
use serde::Deserialize;

pub use crate::engine::PerformerConfig;

/// Default frame port.
pub const DEFAULT_LISTEN: &str = "127.0.0.1:9000";
/// Default control port.
pub const DEFAULT_CONTROL: &str = "127.0.0.1:9001";
/// Default frames queued for the processing thread (latest frame wins past it).
pub const DEFAULT_QUEUE: usize = 64;
/// Default polling window around a steady source's expected arrival, µs (see
/// [`super::arrival`]).
pub const DEFAULT_POLL_WINDOW_US: u64 = 400;
/// Default interval between status log lines.
pub const DEFAULT_STATS_INTERVAL_S: f64 = 5.0;

/// One `[[performers]]` table.
#[derive(Debug, Clone, Default, Deserialize, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct RawPerformer {
    /// Name, for logs.
    pub name: String,
    /// Model file (the loaded model when absent).
    pub model: Option<PathBuf>,
    /// Sender address `IP:PORT` whose frames are this performer's.
    pub source: Option<String>,
    /// Layout id whose frames are this performer's.
    pub layout: Option<i32>,
    /// Default target emotion.
    pub emotion: Option<String>,
    /// Default amount.
    pub amount: Option<f32>,
}

/// The TOML file as written, every key optional.
#[derive(Debug, Clone, Default, Deserialize, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct RawConfig {
    /// Frame socket address.
    pub listen: Option<String>,
    /// Control socket address.
    pub control: Option<String>,
    /// Model file.
    pub model: Option<PathBuf>,
    /// Static subscribers `HOST:PORT[:profile]`.
    pub send: Vec<String>,
    /// Cap on `/subscribe` subscribers.
    pub max_subscribers: Option<usize>,
    /// Failed sends before a subscriber is dropped.
    pub max_send_failures: Option<u32>,
    /// Low-pass window of the emotion edit, seconds.
    pub lowpass_s: Option<f32>,
    /// Frames queued for processing.
    pub queue: Option<usize>,
    /// Polling window around the expected arrival, µs; 0 always parks.
    pub poll_window_us: Option<u64>,
    /// Seconds between status log lines.
    pub stats_interval_s: Option<f64>,
    /// Named performers.
    pub performers: Vec<RawPerformer>,
}

/// The validated configuration; the only form that travels on.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// Frame socket address (port 0 = any free port).
    pub listen: SocketAddr,
    /// Control socket address.
    pub control: SocketAddr,
    /// Model file.
    pub model: PathBuf,
    /// Static subscribers.
    pub send: Vec<(SocketAddr, Profile)>,
    /// Cap on dynamic subscribers.
    pub max_subscribers: usize,
    /// Failed sends before a subscriber is dropped.
    pub max_send_failures: u32,
    /// Low-pass window, seconds.
    pub lowpass_s: f32,
    /// Processing queue length.
    pub queue: usize,
    /// Polling window around a steady source's expected arrival.
    pub poll_window: Duration,
    /// Status log interval.
    pub stats_interval: Duration,
    /// Performers.
    pub performers: Vec<PerformerConfig>,
}

/// Why a configuration is refused; each names the key and the value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// The TOML does not parse, or has an unknown key (toml names it).
    #[error("{0}")]
    Toml(String),
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
    /// No model given.
    #[error("no model: pass --model model.json or set model in the config")]
    NoModel,
}

impl RawConfig {
    /// Parses a TOML text.
    ///
    /// # Errors
    /// [`ConfigError::Toml`] with toml's message, which names an unknown key.
    pub fn from_toml(text: &str) -> Result<RawConfig, ConfigError> {
        toml::from_str(text).map_err(|e| ConfigError::Toml(e.message().to_string()))
    }

    /// Checks every value once.
    ///
    /// # Errors
    /// The first bad value, named.
    pub fn validate(self) -> Result<Config, ConfigError> {
        let addr = |key: &'static str, v: Option<String>, default: &str| {
            let v = v.unwrap_or_else(|| default.to_string());
            v.parse::<SocketAddr>()
                .map_err(|_| ConfigError::Address { key, value: v })
        };
        let range = |key, ok: bool, value: String, range| {
            if ok {
                Ok(())
            } else {
                Err(ConfigError::Range { key, value, range })
            }
        };
        let lowpass_s = self
            .lowpass_s
            .unwrap_or(crate::engine::edit_state::DEFAULT_LOWPASS_S);
        range(
            "lowpass_s",
            lowpass_s.is_finite() && lowpass_s >= 0.0,
            lowpass_s.to_string(),
            ">= 0",
        )?;
        let queue = self.queue.unwrap_or(DEFAULT_QUEUE);
        range(
            "queue",
            (1..=65_536).contains(&queue),
            queue.to_string(),
            "1..=65536",
        )?;
        let poll_window_us = self.poll_window_us.unwrap_or(DEFAULT_POLL_WINDOW_US);
        range(
            "poll_window_us",
            poll_window_us <= 1_000,
            poll_window_us.to_string(),
            "0..=1000",
        )?;
        let stats = self.stats_interval_s.unwrap_or(DEFAULT_STATS_INTERVAL_S);
        range(
            "stats_interval_s",
            stats.is_finite() && stats > 0.0,
            stats.to_string(),
            "> 0",
        )?;
        let send = self
            .send
            .iter()
            .map(|s| parse_send(s))
            .collect::<Result<_, _>>()?;
        let performers = self
            .performers
            .into_iter()
            .map(|p| {
                let source = p
                    .source
                    .map(|s| {
                        s.parse().map_err(|_| ConfigError::Address {
                            key: "performers.source",
                            value: s,
                        })
                    })
                    .transpose()?;
                Ok(PerformerConfig {
                    name: p.name,
                    model: p.model,
                    source,
                    layout: p.layout,
                    target: p.emotion,
                    amount: p.amount,
                })
            })
            .collect::<Result<_, ConfigError>>()?;
        Ok(Config {
            listen: addr("listen", self.listen, DEFAULT_LISTEN)?,
            control: addr("control", self.control, DEFAULT_CONTROL)?,
            model: self.model.ok_or(ConfigError::NoModel)?,
            send,
            max_subscribers: self
                .max_subscribers
                .unwrap_or(crate::engine::clients::DEFAULT_MAX_DYNAMIC),
            max_send_failures: self
                .max_send_failures
                .unwrap_or(crate::engine::clients::DEFAULT_MAX_FAILURES),
            lowpass_s,
            queue,
            poll_window: Duration::from_micros(poll_window_us),
            stats_interval: Duration::from_secs_f64(stats),
            performers,
        })
    }
}

/// Parses `HOST:PORT[:profile]` (IPv6 as `[::1]:PORT[:profile]`); compact by default.
///
/// # Errors
/// [`ConfigError::Address`] or [`ConfigError::Profile`].
pub fn parse_send(text: &str) -> Result<(SocketAddr, Profile), ConfigError> {
    if let Ok(addr) = text.parse::<SocketAddr>() {
        return Ok((addr, Profile::Compact));
    }
    let (head, profile) = text.rsplit_once(':').ok_or_else(|| ConfigError::Address {
        key: "send",
        value: text.to_string(),
    })?;
    let addr = head.parse().map_err(|_| ConfigError::Address {
        key: "send",
        value: text.to_string(),
    })?;
    let profile = Profile::parse(profile).ok_or_else(|| ConfigError::Profile {
        value: text.to_string(),
    })?;
    Ok((addr, profile))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_bind_loopback_and_unknown_keys_are_named() {
        let c = RawConfig::from_toml("model = \"m.json\"")
            .expect("valid")
            .validate()
            .expect("valid");
        assert!(c.listen.ip().is_loopback() && c.control.ip().is_loopback());
        assert_eq!(c.max_subscribers, 16);
        let e = RawConfig::from_toml("model = \"m.json\"\nlisten_port = 3").expect_err("unknown");
        assert!(e.to_string().contains("listen_port"), "{e}");
    }

    #[test]
    fn the_example_config_parses_and_holds_the_defaults() {
        let text = include_str!("../../../docs/emoshift.toml");
        let c = RawConfig::from_toml(text)
            .expect("the example parses")
            .validate()
            .expect("the example is valid");
        let d = RawConfig {
            model: Some("model.json".into()),
            ..RawConfig::default()
        };
        assert_eq!(c, d.validate().expect("defaults are valid"));
    }

    #[test]
    fn send_entries_take_a_profile_and_bad_values_are_named() {
        assert_eq!(
            parse_send("239.0.0.1:9100:flat-split"),
            Ok(("239.0.0.1:9100".parse().expect("addr"), Profile::FlatSplit))
        );
        assert_eq!(parse_send("[::1]:9100").map(|s| s.1), Ok(Profile::Compact));
        assert!(matches!(
            parse_send("127.0.0.1:9:loud"),
            Err(ConfigError::Profile { .. })
        ));
        let raw = RawConfig {
            model: Some("m".into()),
            lowpass_s: Some(-1.0),
            ..RawConfig::default()
        };
        assert!(raw
            .validate()
            .expect_err("negative")
            .to_string()
            .contains("lowpass_s"));
        let raw = RawConfig {
            model: Some("m".into()),
            poll_window_us: Some(5_000),
            ..RawConfig::default()
        };
        assert!(raw
            .validate()
            .expect_err("a 5 ms window would poll most of the period")
            .to_string()
            .contains("poll_window_us"));
        assert_eq!(RawConfig::default().validate(), Err(ConfigError::NoModel));
    }
}
