//! Who may control the daemon, and how: the control allow-list, the shared secret of mutating
//! controls, the cookie a subscription from beyond loopback must echo, and refusals logged at
//! WARN without letting a flood of them flood the log.

use std::collections::hash_map::RandomState;
use std::hash::BuildHasher;
use std::net::SocketAddr;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use protocol::{decode_control, decode_control_with_secret, Control};

use super::allow::AllowList;
use super::command::Refusal;
use super::Config;

/// A cookie stays valid this long (and one period more).
const COOKIE_PERIOD: Duration = Duration::from_secs(30);
/// At most one refusal warning this often; the others are counted into the next.
const WARN_EVERY: Duration = Duration::from_secs(5);

/// The control socket's rules, shared by the control task and the monitor.
#[derive(Debug)]
pub(crate) struct Guard {
    allow: AllowList,
    secret: Option<String>,
    /// Keys the cookie hash; random per run, so cookies cannot be computed elsewhere.
    cookie_key: RandomState,
    started: Instant,
    /// Largest model file `/model/load` reads.
    pub(crate) max_model_bytes: u64,
    warnings: Mutex<Warnings>,
}

#[derive(Debug)]
struct Warnings {
    last: Option<Instant>,
    suppressed: u64,
}

impl Guard {
    /// The rules of `config`.
    pub(crate) fn new(config: &Config) -> Guard {
        let mut guard =
            Guard::with_rules(config.control_allow.clone(), config.control_secret.clone());
        guard.max_model_bytes = config.max_model_bytes;
        guard
    }

    /// Who may control (`allow`), and the secret mutating controls carry when one is set: the
    /// rules of another control socket than serve's (`emoshift session`).
    pub(crate) fn with_rules(allow: AllowList, secret: Option<String>) -> Guard {
        Guard {
            allow,
            secret,
            cookie_key: RandomState::new(),
            started: Instant::now(),
            max_model_bytes: super::config::DEFAULT_MAX_MODEL_MB << 20,
            warnings: Mutex::new(Warnings {
                last: None,
                suppressed: 0,
            }),
        }
    }

    /// Whether mutating controls must carry the shared secret.
    pub(crate) fn needs_secret(&self) -> bool {
        self.secret.is_some()
    }

    /// Whether `peer` may send control messages at all.
    ///
    /// # Errors
    /// [`Refusal::NotAllowed`].
    pub(crate) fn admit(&self, peer: SocketAddr) -> Result<(), Refusal> {
        match self.allow.allows(peer.ip()) {
            true => Ok(()),
            false => Err(Refusal::NotAllowed(peer.ip())),
        }
    }

    /// Decodes a control message, requiring the secret on mutating ones when one is set.
    ///
    /// # Errors
    /// [`Refusal::Invalid`] for a malformed message or a bad value, [`Refusal::Secret`] for a
    /// mutating control without the secret.
    pub(crate) fn decode(&self, bytes: &[u8]) -> Result<Control, Refusal> {
        let invalid = |e: protocol::ControlError| Refusal::Invalid(e.to_string());
        let Some(secret) = &self.secret else {
            return decode_control(bytes).map_err(invalid);
        };
        let (control, signed) = decode_control_with_secret(bytes, secret).map_err(invalid)?;
        self.check_signed(&control, signed)?;
        Ok(control)
    }

    /// A control that did not come as bytes (the monitor page) against the secret rule.
    ///
    /// # Errors
    /// [`Refusal::Secret`] for a mutating control without the secret.
    pub(crate) fn check_signed(&self, control: &Control, signed: bool) -> Result<(), Refusal> {
        match self.secret.is_some() && control.is_mutating() && !signed {
            true => Err(Refusal::Secret),
            false => Ok(()),
        }
    }

    /// Whether a `/subscribe` from `peer` may go ahead: from this host (127.0.0.1 or ::1)
    /// always, from elsewhere only with the cookie this daemon gave that address for that
    /// subscription. `Err` holds the cookie to send in `/subscribe/challenge`. The other
    /// 127.x addresses count as elsewhere, so a test can stand in for a second host.
    pub(crate) fn check_cookie(&self, peer: SocketAddr, control: &Control) -> Result<(), i32> {
        let Control::Subscribe { cookie, .. } = control else {
            return Ok(());
        };
        let this_host = match peer.ip() {
            std::net::IpAddr::V4(v4) => v4 == std::net::Ipv4Addr::LOCALHOST,
            std::net::IpAddr::V6(v6) => v6 == std::net::Ipv6Addr::LOCALHOST,
        };
        if this_host {
            return Ok(());
        }
        let period = self.started.elapsed().as_secs() / COOKIE_PERIOD.as_secs();
        let now = self.cookie(peer, control, period);
        let before = self.cookie(peer, control, period.saturating_sub(1));
        match *cookie {
            Some(c) if c == now || c == before => Ok(()),
            _ => Err(now),
        }
    }

    /// A keyed hash of who asked (address and port), what for, and when.
    fn cookie(&self, peer: SocketAddr, control: &Control, period: u64) -> i32 {
        let Control::Subscribe {
            port,
            profile,
            performer,
            ..
        } = control
        else {
            return 0;
        };
        let h = self
            .cookie_key
            .hash_one((peer, *port, profile.as_str(), performer, period));
        // Positive, so that hand-typed tools that take only positive ints can echo it.
        (h & 0x7fff_ffff) as i32
    }

    /// Logs a refusal at WARN, at most once per [`WARN_EVERY`], saying how many were not logged.
    pub(crate) fn warn_refused(&self, peer: SocketAddr, address: &str, refusal: &Refusal) {
        let Ok(mut w) = self.warnings.lock() else {
            return;
        };
        let now = Instant::now();
        if w.last.is_some_and(|t| now.duration_since(t) < WARN_EVERY) {
            w.suppressed += 1;
            return;
        }
        let more = std::mem::take(&mut w.suppressed);
        w.last = Some(now);
        tracing::warn!(target: "emoshift", %peer, address, error = %refusal, more_not_logged = more, "control refused");
    }
}
