//! Subscribers, sans-IO: static ones from the config or CLI (multicast allowed), dynamic ones
//! from `/subscribe`, which may only name a port on the requester's own IP (so the daemon
//! can never be used to reflect traffic at a third party) and are capped (16 by default).
//! Dynamic subscriptions expire unless renewed; any subscriber whose sends keep failing
//! (ICMP port unreachable surfaces as a send error on its connected socket) is dropped.
//!
//! Call order: [`Clients::handle_control`] per control message, [`Clients::handle_send`] per
//! send result, [`Clients::poll_expired`] now and then. The caller owns sockets and clock.

use core::net::SocketAddr;
use std::time::{Duration, Instant};

use protocol::{Control, Profile};

/// Dynamic subscribers at most, by default.
pub const DEFAULT_MAX_DYNAMIC: usize = 16;
/// Failures (not offset by [`SUCCESSES_TO_FORGIVE`] successes) before a subscriber is dropped.
pub const DEFAULT_MAX_FAILURES: u32 = 8;
/// Consecutive successful sends that clear a subscriber's failure count. An unreachable port
/// fails only every other send (the ICMP error arrives after the datagram that caused it), so
/// the count must not reset on a single success.
pub const SUCCESSES_TO_FORGIVE: u32 = 64;
/// A dynamic subscription lasts this long unless `/subscribe` is sent again.
pub const DEFAULT_LEASE: Duration = Duration::from_secs(300);

/// One destination.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Subscriber {
    /// Where to send.
    pub addr: SocketAddr,
    /// What to send.
    pub profile: Profile,
    /// Came from the config (never expires).
    pub is_static: bool,
    failures: u32,
    successes: u32,
    expires: Option<Instant>,
}

/// What a control message did to the subscriber set.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ClientChange {
    /// A subscriber was added (the caller opens its socket).
    Added(SocketAddr),
    /// An existing subscription was renewed or its profile changed.
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
    /// Not a subscription message.
    #[error("not a subscription message")]
    NotSubscription,
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
    /// A set with `statics` and room for `max_dynamic` dynamic subscribers.
    pub fn new(statics: &[(SocketAddr, Profile)], max_dynamic: usize, max_failures: u32) -> Self {
        let list = statics
            .iter()
            .map(|&(addr, profile)| Subscriber {
                addr,
                profile,
                is_static: true,
                failures: 0,
                successes: 0,
                expires: None,
            })
            .collect();
        Clients {
            list,
            max_dynamic,
            max_failures: max_failures.max(1),
            lease: DEFAULT_LEASE,
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

    /// Handles `/subscribe` or `/unsubscribe` from `peer`: the destination is always the
    /// peer's own IP at the port named.
    ///
    /// # Errors
    /// [`ClientError`] naming why.
    pub fn handle_control(
        &mut self,
        now: Instant,
        peer: SocketAddr,
        msg: &Control,
    ) -> Result<ClientChange, ClientError> {
        match *msg {
            Control::Subscribe { port, profile } => {
                let addr = SocketAddr::new(peer.ip(), port);
                let expires = Some(now + self.lease);
                if let Some(s) = self.list.iter_mut().find(|s| s.addr == addr) {
                    s.profile = profile;
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
                self.list.push(Subscriber {
                    addr,
                    profile,
                    is_static: false,
                    failures: 0,
                    successes: 0,
                    expires,
                });
                Ok(ClientChange::Added(addr))
            }
            Control::Unsubscribe { port } => {
                let addr = SocketAddr::new(peer.ip(), port);
                let before = self.list.len();
                self.list.retain(|s| s.addr != addr);
                if self.list.len() == before {
                    return Err(ClientError::NotSubscribed { addr });
                }
                Ok(ClientChange::Removed(addr))
            }
            _ => Err(ClientError::NotSubscription),
        }
    }

    /// Records one send to `addr`; returns `true` when the subscriber was dropped for
    /// repeated failures.
    pub fn handle_send(&mut self, addr: SocketAddr, ok: bool) -> bool {
        let Some(i) = self.list.iter().position(|s| s.addr == addr) else {
            return false;
        };
        let s = &mut self.list[i];
        if ok {
            s.successes += 1;
            if s.successes >= SUCCESSES_TO_FORGIVE {
                s.failures = 0;
            }
            return false;
        }
        s.successes = 0;
        s.failures += 1;
        if s.failures < self.max_failures {
            return false;
        }
        self.list.remove(i);
        true
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
mod tests {
    use super::*;

    fn addr(s: &str) -> SocketAddr {
        s.parse().expect("literal address")
    }

    fn sub(port: u16) -> Control {
        Control::Subscribe {
            port,
            profile: Profile::Compact,
        }
    }

    #[test]
    fn subscribe_goes_to_the_requesters_own_ip_and_is_capped() {
        let now = Instant::now();
        let mut c = Clients::new(&[(addr("239.1.2.3:9000"), Profile::Compact)], 2, 3);
        let peer = addr("127.0.0.5:40000");
        assert_eq!(
            c.handle_control(now, peer, &sub(7000)),
            Ok(ClientChange::Added(addr("127.0.0.5:7000")))
        );
        assert_eq!(
            c.handle_control(now, peer, &sub(7000)),
            Ok(ClientChange::Renewed(addr("127.0.0.5:7000")))
        );
        c.handle_control(now, peer, &sub(7001))
            .expect("room for two");
        assert_eq!(
            c.handle_control(now, peer, &sub(7002)),
            Err(ClientError::Full { max: 2 })
        );
        assert_eq!(c.len(), 3, "the static multicast one does not count");
        assert_eq!(
            c.handle_control(now, peer, &Control::Unsubscribe { port: 7000 }),
            Ok(ClientChange::Removed(addr("127.0.0.5:7000")))
        );
    }

    #[test]
    fn repeated_failures_drop_a_subscriber_even_when_interleaved_with_successes() {
        let mut c = Clients::new(&[(addr("127.0.0.1:9"), Profile::Compact)], 16, 3);
        let a = addr("127.0.0.1:9");
        assert!(!c.handle_send(a, false));
        assert!(!c.handle_send(a, true));
        assert!(!c.handle_send(a, false));
        assert!(c.handle_send(a, false));
        assert!(c.is_empty());
    }

    #[test]
    fn dynamic_subscriptions_expire_static_ones_do_not() {
        let now = Instant::now();
        let mut c = Clients::new(&[(addr("127.0.0.1:9"), Profile::Compact)], 16, 3);
        c.handle_control(now, addr("127.0.0.1:1"), &sub(7000))
            .expect("room");
        assert!(c.poll_expired(now + Duration::from_secs(1)).is_empty());
        assert_eq!(
            c.poll_expired(now + DEFAULT_LEASE),
            vec![addr("127.0.0.1:7000")]
        );
        assert_eq!(c.len(), 1);
    }
}
