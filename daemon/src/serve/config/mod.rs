//! Configuration of `emoshift serve`, in two stages: [`RawConfig`] (TOML, every key optional,
//! unknown keys rejected by name) with CLI flags laid over it, then one [`RawConfig::validate`]
//! into a [`Config`]. Defaults bind loopback only.

use std::collections::HashMap;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use protocol::Profile;
use serde::Deserialize;

use super::allow::AllowList;
pub use super::config_error::ConfigError;

mod exposure;
mod values;
pub(crate) use values::check_token;
pub use values::parse_send;
use values::{addr, check, performer, secret};

pub use engine::PerformerConfig;

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
/// Default largest model file, MB: a 109-marker model is well under 1 MB.
pub const DEFAULT_MAX_MODEL_MB: u64 = 256;

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
    /// NatNet markerset (Motive asset) whose frames are this performer's.
    pub markerset: Option<String>,
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
    /// Model file; without one, frames pass through unedited until `/model/load`.
    pub model: Option<PathBuf>,
    /// Rate announced and recorded for streams passed through without a model, Hz.
    pub passthrough_rate_hz: Option<f64>,
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
    /// Seconds a `/subscribe` lasts unless renewed.
    pub subscription_lease_s: Option<f64>,
    /// Networks allowed on the control socket (CIDR); loopback only when absent.
    pub control_allow: Option<Vec<String>>,
    /// Networks allowed on the frame socket (CIDR); anyone when absent.
    pub frames_allow: Option<Vec<String>>,
    /// Shared secret that mutating control messages must carry as their last argument.
    pub control_secret: Option<String>,
    /// Largest model file `/model/load` and SIGHUP read, MB.
    pub max_model_mb: Option<u64>,
    /// Named performers.
    pub performers: Vec<RawPerformer>,
    /// NatNet server to take frames from, `IP[:PORT]` (see [`super::sources::natnet`]).
    pub natnet: Option<String>,
    /// Where NatNet frames arrive (multicast group or local address), `IP:PORT`.
    pub natnet_data: Option<String>,
    /// Local IPv4 address the NatNet multicast group is joined on.
    pub natnet_interface: Option<String>,
    /// Rate of the NatNet source's timecode (`29.97df`, `30`, ...).
    pub natnet_timecode_rate: Option<String>,
    /// How NatNet markers are named: `asset:marker`, `asset_marker` or `marker`.
    pub natnet_names: Option<String>,
    /// NatNet marker names (as built) to model labels.
    pub natnet_rename: HashMap<String, String>,
    /// The NatNet server's command address, `IP[:PORT]` (see [`super::sinks::natnet`]).
    pub natnet_server: Option<String>,
    /// The NatNet server's multicast group, `GROUP[:PORT]` (unicast when absent).
    pub natnet_server_multicast: Option<String>,
    /// Local IPv4 address the NatNet server multicasts on.
    pub natnet_server_interface: Option<String>,
    /// The NatNet server's default bitstream (`3.1`, `4.1`).
    pub natnet_server_version: Option<String>,
    /// A `<name>_raw` markerset with each performer's unedited input too.
    pub natnet_server_raw: Option<bool>,
    /// Unicast NatNet clients at most.
    pub natnet_server_max_clients: Option<usize>,
    /// The components profile's blend names (`emotion`, `speech1`, ...) to the names receivers
    /// want (an avatar's blendshapes).
    pub vmc_names: HashMap<String, String>,
    /// QTM's RT address, `HOST[:PORT]`: a QTM source (see [`super::sources::qtm`]).
    pub qtm: Option<String>,
    /// QTM performers: name to label pattern (`alice = "Alice_*"`).
    pub qtm_performers: std::collections::BTreeMap<String, String>,
    /// The QTM server's RT address, `IP[:PORT]` (see [`super::sinks::qtm`]).
    pub qtm_server: Option<String>,
    /// QTM clients at most.
    pub qtm_server_max_clients: Option<usize>,
    /// Where QTM discovery is answered, `IP[:PORT]`, or `off`.
    pub qtm_server_discovery: Option<String>,
    /// The monitor page's address (off when absent).
    pub monitor: Option<String>,
    /// The monitor page's token (generated and printed when the page is bound beyond
    /// loopback and none is set).
    pub monitor_token: Option<String>,
}

/// The validated configuration; the only form that travels on.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// Frame socket address (port 0 = any free port).
    pub listen: SocketAddr,
    /// Control socket address.
    pub control: SocketAddr,
    /// Model file; `None`: frames pass through unedited until a model is loaded
    /// (`/model/load`).
    pub model: Option<PathBuf>,
    /// Rate of streams passed through without a model (their recordings, the NatNet and QTM
    /// servers' announced rate), Hz.
    pub passthrough_rate_hz: f64,
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
    /// How long a dynamic subscription lasts unless renewed.
    pub lease: Duration,
    /// Who may send control messages.
    pub control_allow: AllowList,
    /// Who may send frames.
    pub frames_allow: AllowList,
    /// The shared secret of mutating control messages, if any.
    pub control_secret: Option<String>,
    /// Largest model file read, bytes.
    pub max_model_bytes: u64,
    /// Performers.
    pub performers: Vec<PerformerConfig>,
    /// The NatNet source, if any.
    pub natnet: Option<super::sources::natnet::NatNetConfig>,
    /// The NatNet server, if any.
    pub natnet_server: Option<super::sinks::natnet::NatNetServerConfig>,
    /// The components profile's blend names to the names sent instead.
    pub vmc_names: HashMap<String, String>,
    /// The QTM source, if any.
    pub qtm: Option<super::sources::qtm::QtmConfig>,
    /// The QTM server, if any.
    pub qtm_server: Option<super::sinks::qtm::QtmServerConfig>,
    /// The monitor page's address, if it is served.
    pub monitor: Option<SocketAddr>,
    /// The monitor page's token, if one is set.
    pub monitor_token: Option<String>,
}

impl RawConfig {
    /// Parses a TOML text.
    ///
    /// # Errors
    /// [`ConfigError::Toml`] naming the line, the key and what is wrong (an unknown key, a
    /// value of the wrong type, broken syntax).
    pub fn from_toml(text: &str) -> Result<RawConfig, ConfigError> {
        toml::from_str(text).map_err(|e| {
            let line = e.span().map_or(0, |s| {
                text[..s.start.min(text.len())].lines().count().max(1)
            });
            let key = (line > 0)
                .then(|| text.lines().nth(line - 1))
                .flatten()
                .and_then(|l| l.split_once('='))
                .map(|(k, _)| k.trim().to_string())
                .filter(|k| !k.is_empty());
            ConfigError::Toml {
                line,
                key,
                message: e.message().trim().to_string(),
            }
        })
    }

    /// Checks every value once.
    ///
    /// # Errors
    /// The first bad value, named.
    pub fn validate(mut self) -> Result<Config, ConfigError> {
        let numbers = self.numbers()?;
        let natnet = self.take_natnet().validate()?;
        let natnet_server = self.take_natnet_server().validate()?;
        let qtm_server = self.take_qtm_server().validate()?;
        let qtm = self.take_qtm().validate()?;
        let send = self
            .send
            .iter()
            .map(|s| parse_send(s))
            .collect::<Result<_, _>>()?;
        let allow = |key, list: Option<Vec<String>>, default: AllowList| match list {
            Some(l) => {
                AllowList::parse(&l).map_err(|message| ConfigError::Network { key, message })
            }
            None => Ok(default),
        };
        let listen = addr("listen", self.listen, DEFAULT_LISTEN)?;
        let control = addr("control", self.control, DEFAULT_CONTROL)?;
        if shares_port(listen, control) {
            return Err(ConfigError::SharedPort { listen, control });
        }
        Ok(Config {
            listen,
            control,
            model: self.model,
            passthrough_rate_hz: numbers.passthrough_rate_hz,
            send,
            max_subscribers: self
                .max_subscribers
                .unwrap_or(engine::subscribers::DEFAULT_MAX_DYNAMIC),
            max_send_failures: self
                .max_send_failures
                .unwrap_or(engine::subscribers::DEFAULT_MAX_FAILURES),
            lowpass_s: numbers.lowpass_s,
            queue: numbers.queue,
            poll_window: numbers.poll_window,
            stats_interval: numbers.stats_interval,
            lease: numbers.lease,
            control_allow: allow("control_allow", self.control_allow, AllowList::loopback())?,
            frames_allow: allow("frames_allow", self.frames_allow, AllowList::anyone())?,
            control_secret: secret(self.control_secret)?,
            max_model_bytes: numbers.max_model_bytes,
            performers: self
                .performers
                .into_iter()
                .map(performer)
                .collect::<Result<_, _>>()?,
            natnet,
            natnet_server,
            vmc_names: self.vmc_names,
            qtm_server,
            qtm,
            monitor: self
                .monitor
                .map(|m| addr("monitor", Some(m), ""))
                .transpose()?,
            monitor_token: check_token(self.monitor_token)?,
        })
    }

    /// The `natnet*` keys, taken out for the NatNet source's own check.
    fn take_natnet(&mut self) -> super::sources::natnet::RawNatNet {
        super::sources::natnet::RawNatNet {
            server: self.natnet.take(),
            data: self.natnet_data.take(),
            interface: self.natnet_interface.take(),
            timecode_rate: self.natnet_timecode_rate.take(),
            names: self.natnet_names.take(),
            rename: std::mem::take(&mut self.natnet_rename),
        }
    }

    /// The `natnet_server*` keys, taken out for the NatNet server's own check.
    fn take_natnet_server(&mut self) -> super::sinks::natnet::RawNatNetServer {
        super::sinks::natnet::RawNatNetServer {
            server: self.natnet_server.take(),
            multicast: self.natnet_server_multicast.take(),
            interface: self.natnet_server_interface.take(),
            version: self.natnet_server_version.take(),
            raw: self.natnet_server_raw.take(),
            max_clients: self.natnet_server_max_clients.take(),
        }
    }

    /// The `qtm` and `qtm_performers` keys, taken out for the QTM source's own check.
    fn take_qtm(&mut self) -> super::sources::qtm::RawQtm {
        super::sources::qtm::RawQtm {
            server: self.qtm.take(),
            performers: std::mem::take(&mut self.qtm_performers),
        }
    }

    /// The `qtm_server*` keys, taken out for the QTM server's own check.
    fn take_qtm_server(&mut self) -> super::sinks::qtm::RawQtmServer {
        super::sinks::qtm::RawQtmServer {
            server: self.qtm_server.take(),
            max_clients: self.qtm_server_max_clients.take(),
            discovery: self.qtm_server_discovery.take(),
        }
    }

    /// The numeric keys, each checked against its range.
    fn numbers(&self) -> Result<Numbers, ConfigError> {
        let lowpass_s = self
            .lowpass_s
            .unwrap_or(engine::edit_state::DEFAULT_LOWPASS_S);
        check(
            "lowpass_s",
            lowpass_s.is_finite() && lowpass_s >= 0.0,
            lowpass_s,
            ">= 0",
        )?;
        let queue = self.queue.unwrap_or(DEFAULT_QUEUE);
        check("queue", (1..=65_536).contains(&queue), queue, "1..=65536")?;
        let poll_us = self.poll_window_us.unwrap_or(DEFAULT_POLL_WINDOW_US);
        check("poll_window_us", poll_us <= 1_000, poll_us, "0..=1000")?;
        let stats = self.stats_interval_s.unwrap_or(DEFAULT_STATS_INTERVAL_S);
        check(
            "stats_interval_s",
            stats.is_finite() && stats > 0.0,
            stats,
            "> 0",
        )?;
        let lease = self
            .subscription_lease_s
            .unwrap_or(engine::subscribers::DEFAULT_LEASE.as_secs_f64());
        let ok = lease.is_finite() && (1.0..=3_600.0).contains(&lease);
        check("subscription_lease_s", ok, lease, "1..=3600")?;
        let mb = self.max_model_mb.unwrap_or(DEFAULT_MAX_MODEL_MB);
        check("max_model_mb", (1..=65_536).contains(&mb), mb, "1..=65536")?;
        let rate = self
            .passthrough_rate_hz
            .unwrap_or(engine::pipeline::DEFAULT_PASSTHROUGH_RATE_HZ);
        let ok = rate.is_finite() && (1.0..=10_000.0).contains(&rate);
        check("passthrough_rate_hz", ok, rate, "1..=10000")?;
        Ok(Numbers {
            passthrough_rate_hz: rate,
            lowpass_s,
            queue,
            poll_window: Duration::from_micros(poll_us),
            stats_interval: Duration::from_secs_f64(stats),
            lease: Duration::from_secs_f64(lease),
            max_model_bytes: mb << 20,
        })
    }
}

/// The numeric settings, checked.
struct Numbers {
    passthrough_rate_hz: f64,
    lowpass_s: f32,
    queue: usize,
    poll_window: Duration,
    stats_interval: Duration,
    lease: Duration,
    max_model_bytes: u64,
}

/// Two UDP sockets that cannot both bind: one port on one address, or on any address
/// (`0.0.0.0` or `::`) and another of the same family.
fn shares_port(a: SocketAddr, b: SocketAddr) -> bool {
    a.port() == b.port()
        && a.port() != 0
        && a.is_ipv4() == b.is_ipv4()
        && (a.ip() == b.ip() || a.ip().is_unspecified() || b.ip().is_unspecified())
}

#[cfg(test)]
mod tests;
