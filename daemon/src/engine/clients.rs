//! Subscribers, sans-IO.
//!
//! - **Static** ones come from the config or `--send` (multicast allowed). They are never
//!   dropped: a target that is not listening yet (ICMP port unreachable surfaces as a send
//!   error on its connected socket) is retried on a back-off of at most [`MAX_BACKOFF`], so a
//!   receiver started late gets frames within a second of starting.
//! - **Dynamic** ones come from `/subscribe`, which may only name a port on the requester's
//!   own IP (so the daemon never sends to a third party), are capped (16 by default) and hold
//!   a lease: a client renews by subscribing again, one that stops renewing is dropped. One
//!   whose sends keep failing is dropped too.
//!
//! A subscriber may ask for one performer's stream only. Every subscriber gets a stream's
//! `/mocap/labels` before that stream's first frame to it, then once a second with the others.
//!
//! Call order: [`Clients::handle_control`] per subscription message, per frame
//! [`Clients::plan`] for each subscriber then [`Clients::handle_send`] with the result, and
//! [`Clients::poll_expired`] now and then. The caller owns sockets and clock.

use core::net::SocketAddr;
use std::time::{Duration, Instant};

use protocol::{Control, Profile};

/// Dynamic subscribers at most, by default.
pub const DEFAULT_MAX_DYNAMIC: usize = 16;
/// Failures (not offset by [`SUCCESSES_TO_FORGIVE`] successes) before a dynamic subscriber is
/// dropped, or a static one backs off.
pub const DEFAULT_MAX_FAILURES: u32 = 8;
/// Consecutive successful sends that clear a subscriber's failure count. An unreachable port
/// fails only every other send (the ICMP error arrives after the datagram that caused it), so
/// the count must not reset on a single success.
pub const SUCCESSES_TO_FORGIVE: u32 = 64;
/// A dynamic subscription lasts this long unless `/subscribe` is sent again.
pub const DEFAULT_LEASE: Duration = Duration::from_secs(10);
/// First back-off of an unreachable static target; it doubles up to [`MAX_BACKOFF`].
pub const FIRST_BACKOFF: Duration = Duration::from_millis(250);
/// Longest back-off of an unreachable static target.
pub const MAX_BACKOFF: Duration = Duration::from_secs(1);

/// One destination.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Subscriber {
    /// Where to send.
    pub addr: SocketAddr,
    /// What to send.
    pub profile: Profile,
    /// Only this performer's stream (`None`: every stream).
    pub performer: Option<String>,
    /// Came from the config (never dropped, never expires).
    pub is_static: bool,
    /// Datagrams sent.
    pub sends: u64,
    /// Sends that failed.
    pub failures_total: u64,
    failures: u32,
    successes: u32,
    expires: Option<Instant>,
    /// While backing off: no send before this.
    retry_at: Option<Instant>,
    backoff: Duration,
    /// Streams whose labels this subscriber has had since it subscribed.
    labelled: Vec<i32>,
}

impl Subscriber {
    fn new(addr: SocketAddr, profile: Profile, is_static: bool) -> Subscriber {
        Subscriber {
            addr,
            profile,
            performer: None,
            is_static,
            sends: 0,
            failures_total: 0,
            failures: 0,
            successes: 0,
            expires: None,
            retry_at: None,
            backoff: Duration::ZERO,
            labelled: Vec::new(),
        }
    }

    /// Time left on the lease (`None` for a static subscriber).
    pub fn lease_left(&self, now: Instant) -> Option<Duration> {
        self.expires.map(|e| e.saturating_duration_since(now))
    }

    /// Backing off after repeated failures (a static target not listening).
    pub fn is_backing_off(&self) -> bool {
        self.retry_at.is_some()
    }
}

/// What a control message did to the subscriber set.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ClientChange {
    /// A subscriber was added (the caller opens its socket).
    Added(SocketAddr),
    /// An existing subscription was renewed, or its profile or performer changed.
    Renewed(SocketAddr),
    /// A subscriber was removed (the caller closes its socket).
    Removed(SocketAddr),
}

/// Why `/subscribe` or `/unsubscribe` was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ClientError {
    /// The dynamic cap is reached.
    #[error("subscriber limit {max} reached")]
    Full {
        /// The cap.
        max: usize,
    },
    /// `/unsubscribe` for a port with no subscription.
    #[error("no subscription for {addr}")]
    NotSubscribed {
        /// The address named.
        addr: SocketAddr,
    },
    /// `/unsubscribe` of a subscriber from the config.
    #[error("{addr} is a configured target and stays")]
    Static {
        /// The address named.
        addr: SocketAddr,
    },
    /// Not a subscription message.
    #[error("not a subscription message")]
    NotSubscription,
}

/// What to send one subscriber for one frame of a stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Plan {
    /// Send the frame at all (its performer, not backing off).
    pub send: bool,
    /// Send the stream's labels first.
    pub labels: bool,
}

/// What one send did to its subscriber.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SendOutcome {
    /// It went out.
    Sent,
    /// It failed; counted.
    Failed,
    /// A static target failed once too often: no sends for this long.
    BackingOff(Duration),
    /// A dynamic subscriber failed once too often and was removed (close its socket).
    Dropped,
    /// A static target that was backing off took a send again.
    Recovered,
}

/// The subscriber set. See the module docs for the call order.
#[derive(Debug, Clone)]
pub struct Clients {
    list: Vec<Subscriber>,
    max_dynamic: usize,
    max_failures: u32,
    lease: Duration,
}

impl Clients {
    /// A set with `statics`, room for `max_dynamic` dynamic subscribers, each leased for
    /// `lease`.
    pub fn new(
        statics: &[(SocketAddr, Profile)],
        max_dynamic: usize,
        max_failures: u32,
        lease: Duration,
    ) -> Self {
        let list = statics
            .iter()
            .map(|&(addr, profile)| Subscriber::new(addr, profile, true))
            .collect();
        Clients {
            list,
            max_dynamic,
            max_failures: max_failures.max(1),
            lease,
        }
    }

    /// Every subscriber.
    pub fn iter(&self) -> impl Iterator<Item = &Subscriber> {
        self.list.iter()
    }

    /// The `i`-th subscriber.
    pub fn get(&self, i: usize) -> Option<&Subscriber> {
        self.list.get(i)
    }

    /// Subscribers now.
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// No subscriber.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// The profiles wanted, as a bit set.
    pub fn wanted(&self) -> super::pipeline::ProfileMask {
        self.list
            .iter()
            .fold(0, |m, s| m | super::pipeline::profile_bit(s.profile))
    }

    /// Handles `/subscribe` or `/unsubscribe` from `peer` (a `/subscribe` from beyond
    /// loopback only once its cookie was checked): the destination is always the peer's own IP
    /// at the port named.
    ///
    /// # Errors
    /// [`ClientError`] naming why.
    pub fn handle_control(
        &mut self,
        now: Instant,
        peer: SocketAddr,
        msg: &Control,
    ) -> Result<ClientChange, ClientError> {
        match msg {
            Control::Subscribe {
                port,
                profile,
                performer,
                ..
            } => self.subscribe(now, SocketAddr::new(peer.ip(), *port), *profile, performer),
            Control::Unsubscribe { port } => {
                let addr = SocketAddr::new(peer.ip(), *port);
                match self.list.iter().position(|s| s.addr == addr) {
                    None => Err(ClientError::NotSubscribed { addr }),
                    Some(i) if self.list[i].is_static => Err(ClientError::Static { addr }),
                    Some(i) => {
                        self.list.remove(i);
                        Ok(ClientChange::Removed(addr))
                    }
                }
            }
            _ => Err(ClientError::NotSubscription),
        }
    }

    fn subscribe(
        &mut self,
        now: Instant,
        addr: SocketAddr,
        profile: Profile,
        performer: &Option<String>,
    ) -> Result<ClientChange, ClientError> {
        let expires = Some(now + self.lease);
        if let Some(s) = self.list.iter_mut().find(|s| s.addr == addr) {
            if s.profile != profile || s.performer != *performer {
                // Another view of the streams: it needs their labels again.
                s.labelled.clear();
            }
            s.profile = profile;
            s.performer.clone_from(performer);
            if !s.is_static {
                s.expires = expires;
            }
            return Ok(ClientChange::Renewed(addr));
        }
        let dynamic = self.list.iter().filter(|s| !s.is_static).count();
        if dynamic >= self.max_dynamic {
            return Err(ClientError::Full {
                max: self.max_dynamic,
            });
        }
        let mut s = Subscriber::new(addr, profile, false);
        s.performer.clone_from(performer);
        s.expires = expires;
        self.list.push(s);
        Ok(ClientChange::Added(addr))
    }

    /// What to send subscriber `i` for a frame of stream `id` named `name` whose labels are
    /// due to everyone (`labels_due`).
    pub fn plan(
        &mut self,
        i: usize,
        now: Instant,
        (id, name): (i32, &str),
        labels_due: bool,
    ) -> Plan {
        let Some(s) = self.list.get_mut(i) else {
            return Plan {
                send: false,
                labels: false,
            };
        };
        let waiting = s.retry_at.is_some_and(|t| now < t);
        let wanted = s.performer.as_deref().is_none_or(|p| p == name);
        if waiting || !wanted {
            return Plan {
                send: false,
                labels: false,
            };
        }
        let first = !s.labelled.contains(&id);
        if first {
            s.labelled.push(id);
        }
        Plan {
            send: true,
            labels: labels_due || first,
        }
    }

    /// Records one send to subscriber `i`.
    pub fn handle_send(&mut self, i: usize, ok: bool, now: Instant) -> SendOutcome {
        let max_failures = self.max_failures;
        let Some(s) = self.list.get_mut(i) else {
            return SendOutcome::Failed;
        };
        if ok {
            s.sends += 1;
            s.successes += 1;
            if s.successes >= SUCCESSES_TO_FORGIVE {
                s.failures = 0;
                s.backoff = Duration::ZERO;
            }
            if s.retry_at.take().is_some() {
                return SendOutcome::Recovered;
            }
            return SendOutcome::Sent;
        }
        s.failures_total += 1;
        s.successes = 0;
        s.failures += 1;
        if s.failures < max_failures {
            return SendOutcome::Failed;
        }
        if s.is_static {
            s.backoff = (s.backoff * 2).clamp(FIRST_BACKOFF, MAX_BACKOFF);
            s.retry_at = Some(now + s.backoff);
            // It may have started since: it gets its labels again when it comes back.
            s.labelled.clear();
            return SendOutcome::BackingOff(s.backoff);
        }
        self.list.remove(i);
        SendOutcome::Dropped
    }

    /// Removes dynamic subscriptions whose lease ended; returns their addresses.
    pub fn poll_expired(&mut self, now: Instant) -> Vec<SocketAddr> {
        let gone: Vec<SocketAddr> = self
            .list
            .iter()
            .filter(|s| s.expires.is_some_and(|e| e <= now))
            .map(|s| s.addr)
            .collect();
        self.list.retain(|s| !gone.contains(&s.addr));
        gone
    }
}

#[cfg(test)]
#[path = "clients_tests.rs"]
mod tests;
