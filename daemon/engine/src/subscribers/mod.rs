//! Who an output sends to, sans-IO: the bookkeeping every sink with clients shares, whatever
//! its protocol (the OSC output's `/subscribe`rs; a NatNet or QTM server's connected clients).
//! What a client wants (`W`: an OSC profile, a NatNet version) is the sink's business.
//!
//! - **Static** ones come from the config or `--send` (multicast allowed). They are never
//!   dropped: a target that is not listening yet (ICMP port unreachable surfaces as a send
//!   error on its connected socket) is retried on a back-off of at most [`MAX_BACKOFF`], so a
//!   receiver started late gets frames within a second of starting.
//! - **Dynamic** ones come from the clients themselves (the sink checks that a client names
//!   only itself, so the daemon never sends to a third party), are capped (16 by default) and
//!   hold a lease: a client renews by subscribing again, one that stops renewing is dropped.
//!   One whose sends keep failing is dropped too.
//!
//! A subscriber may ask for one performer's stream only. Every subscriber gets a stream's
//! `/mocap/labels` before that stream's first frame to it, then once a second with the others.
//!
//! Call order: [`Subscribers::subscribe`] / [`Subscribers::unsubscribe`] per request, per
//! frame [`Subscribers::plan`] for each subscriber then [`Subscribers::handle_send`] with the
//! result, and [`Subscribers::poll_expired`] now and then. The caller owns sockets and clock.

use core::net::SocketAddr;
use std::time::{Duration, Instant};

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

/// One destination, wanting `W` (an OSC profile, a protocol version).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Subscriber<W> {
    /// Where to send.
    pub addr: SocketAddr,
    /// What to send.
    pub wants: W,
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

impl<W> Subscriber<W> {
    fn new(addr: SocketAddr, wants: W, is_static: bool) -> Subscriber<W> {
        Subscriber {
            addr,
            wants,
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

/// What a request did to the subscriber set.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Change {
    /// A subscriber was added (the caller opens its socket).
    Added(SocketAddr),
    /// An existing subscription was renewed, or what it wants or its performer changed.
    Renewed(SocketAddr),
    /// A subscriber was removed (the caller closes its socket).
    Removed(SocketAddr),
}

/// Why a subscription or its end was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SubscribeError {
    /// The dynamic cap is reached.
    #[error("subscriber limit {max} reached")]
    Full {
        /// The cap.
        max: usize,
    },
    /// Unsubscribing an address with no subscription.
    #[error("no subscription for {addr}")]
    NotSubscribed {
        /// The address named.
        addr: SocketAddr,
    },
    /// Unsubscribing a subscriber from the config.
    #[error("{addr} is a configured target and stays")]
    Static {
        /// The address named.
        addr: SocketAddr,
    },
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
pub struct Subscribers<W> {
    list: Vec<Subscriber<W>>,
    max_dynamic: usize,
    max_failures: u32,
    lease: Duration,
}

impl<W: Clone + PartialEq> Subscribers<W> {
    /// A set with `statics`, room for `max_dynamic` dynamic subscribers, each leased for
    /// `lease`.
    pub fn new(
        statics: &[(SocketAddr, W)],
        max_dynamic: usize,
        max_failures: u32,
        lease: Duration,
    ) -> Self {
        let list = statics
            .iter()
            .map(|(addr, wants)| Subscriber::new(*addr, wants.clone(), true))
            .collect();
        Subscribers {
            list,
            max_dynamic,
            max_failures: max_failures.max(1),
            lease,
        }
    }

    /// Every subscriber.
    pub fn iter(&self) -> impl Iterator<Item = &Subscriber<W>> {
        self.list.iter()
    }

    /// The `i`-th subscriber.
    pub fn get(&self, i: usize) -> Option<&Subscriber<W>> {
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

    /// Subscribes `addr` (the caller checked that the requester may name it) to `wants`,
    /// of one performer's stream only when `performer` is named; renews the lease of an
    /// existing subscription (a static one keeps none).
    ///
    /// # Errors
    /// [`SubscribeError::Full`] when the dynamic cap is reached.
    pub fn subscribe(
        &mut self,
        now: Instant,
        addr: SocketAddr,
        wants: W,
        performer: Option<&str>,
    ) -> Result<Change, SubscribeError> {
        let expires = Some(now + self.lease);
        if let Some(s) = self.list.iter_mut().find(|s| s.addr == addr) {
            if s.wants != wants || s.performer.as_deref() != performer {
                // Another view of the streams: it needs their labels again.
                s.labelled.clear();
            }
            s.wants = wants;
            s.performer = performer.map(String::from);
            if !s.is_static {
                s.expires = expires;
            }
            return Ok(Change::Renewed(addr));
        }
        let dynamic = self.list.iter().filter(|s| !s.is_static).count();
        if dynamic >= self.max_dynamic {
            return Err(SubscribeError::Full {
                max: self.max_dynamic,
            });
        }
        let mut s = Subscriber::new(addr, wants, false);
        s.performer = performer.map(String::from);
        s.expires = expires;
        self.list.push(s);
        Ok(Change::Added(addr))
    }

    /// Ends the subscription of `addr`.
    ///
    /// # Errors
    /// [`SubscribeError::NotSubscribed`], or [`SubscribeError::Static`] for a configured one.
    pub fn unsubscribe(&mut self, addr: SocketAddr) -> Result<Change, SubscribeError> {
        match self.list.iter().position(|s| s.addr == addr) {
            None => Err(SubscribeError::NotSubscribed { addr }),
            Some(i) if self.list[i].is_static => Err(SubscribeError::Static { addr }),
            Some(i) => {
                self.list.remove(i);
                Ok(Change::Removed(addr))
            }
        }
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
mod tests;
