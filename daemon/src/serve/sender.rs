//! Sending, on the processing thread: each frame's encoded bytes go straight from the
//! pipeline's buffers to every subscriber. A relay's path is receive → send; handing the bytes
//! to another thread here would add a wake-up (tens of µs on a loaded machine) to every frame,
//! so the daemon's path stays receive → process → send.
//!
//! One connected, non-blocking std socket per subscriber: an ICMP port unreachable comes back
//! as a send error on it, so a vanished client is dropped, or a static target backs off
//! ([`Clients::handle_send`]). A full socket send buffer drops that datagram (counted) instead
//! of stalling the thread that processes every stream. Each stream's labels go before its
//! first frame to a subscriber, and once a second.

use std::collections::HashMap;
use std::io::ErrorKind;
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use anyhow::Result;
use hdrhistogram::Histogram;
use protocol::{Control, Profile};

use super::net::connect;
use super::stats::{SendCounters, Stats};
use super::Config;
use crate::engine::clients::{ClientChange, Clients, SendOutcome, Subscriber};
use crate::engine::pipeline::{Emitted, ProfileMask};

/// How often dynamic subscriptions are checked for expiry.
const EXPIRY_EVERY: Duration = Duration::from_secs(1);

/// The subscribers and their sockets, owned by the processing thread.
#[derive(Debug)]
pub(crate) struct Fanout {
    clients: Clients,
    sockets: HashMap<SocketAddr, UdpSocket>,
    /// Counters since the start.
    pub(crate) counters: SendCounters,
    /// Processed → sent to the last subscriber, µs, since the last merge.
    pub(crate) sent_us: Histogram<u64>,
    next_expiry: Instant,
}

impl Fanout {
    /// Opens the static subscribers' sockets.
    ///
    /// # Errors
    /// A static subscriber's socket cannot be opened.
    pub(crate) fn new(config: &Config) -> Result<Fanout> {
        let clients = Clients::new(
            &config.send,
            config.max_subscribers,
            config.max_send_failures,
            config.lease,
        );
        let mut sockets = HashMap::new();
        for &(addr, _) in &config.send {
            let s = connect(addr)
                .map_err(|e| anyhow::anyhow!("opening a socket to subscriber {addr}: {e}"))?;
            sockets.insert(addr, s);
        }
        Ok(Fanout {
            clients,
            sockets,
            counters: SendCounters::default(),
            sent_us: Stats::histogram(),
            next_expiry: Instant::now() + EXPIRY_EVERY,
        })
    }

    /// The profiles the subscribers want.
    pub(crate) fn wanted(&self) -> ProfileMask {
        self.clients.wanted()
    }

    /// Subscribers now.
    pub(crate) fn len(&self) -> usize {
        self.clients.len()
    }

    /// Every subscriber, for `/status`.
    pub(crate) fn subscribers(&self) -> impl Iterator<Item = &Subscriber> {
        self.clients.iter()
    }

    /// Handles `/subscribe` or `/unsubscribe` from `peer`.
    ///
    /// # Errors
    /// The refusal, as the text of the error reply.
    pub(crate) fn command(&mut self, peer: SocketAddr, control: &Control) -> Result<(), String> {
        let now = Instant::now();
        match self.clients.handle_control(now, peer, control) {
            Ok(ClientChange::Added(addr)) => match connect(addr) {
                Ok(s) => {
                    self.sockets.insert(addr, s);
                    tracing::info!(target: "emoshift", %addr, "subscriber added");
                    Ok(())
                }
                Err(e) => {
                    let undo = Control::Unsubscribe { port: addr.port() };
                    let _ = self.clients.handle_control(now, peer, &undo);
                    Err(format!("cannot open a socket to {addr}: {e}"))
                }
            },
            Ok(ClientChange::Removed(addr)) => {
                self.sockets.remove(&addr);
                Ok(())
            }
            Ok(ClientChange::Renewed(_)) => Ok(()),
            Err(e) => Err(e.to_string()),
        }
    }

    /// Drops the dynamic subscriptions whose lease ended (checked once a second); `true` when
    /// the set changed.
    pub(crate) fn expire(&mut self, now: Instant) -> bool {
        if now < self.next_expiry {
            return false;
        }
        self.next_expiry = now + EXPIRY_EVERY;
        let gone = self.clients.poll_expired(now);
        for addr in &gone {
            self.sockets.remove(addr);
            tracing::info!(target: "emoshift", %addr, "subscription expired (not renewed)");
        }
        !gone.is_empty()
    }

    /// Sends one processed frame to every subscriber of its stream, in its profile, with the
    /// stream's labels first when they are due; `true` when a subscriber was dropped (the
    /// wanted profiles may have changed).
    pub(crate) fn send(&mut self, e: &Emitted<'_>, processed: Instant) -> bool {
        let mut dropped_any = false;
        let stream = (e.identity.id, e.identity.name.as_str());
        let mut i = 0;
        while let Some(s) = self.clients.get(i) {
            let (addr, profile) = (s.addr, s.profile);
            let plan = self.clients.plan(i, processed, stream, e.labels_due);
            if !plan.send {
                i += 1;
                continue;
            }
            let ok = match self.sockets.get(&addr) {
                Some(sock) => {
                    let labels_ok = !plan.labels
                        || e.labels_msg.is_empty()
                        || send_one(sock, e.labels_msg, &mut self.counters);
                    labels_ok && send_profile(sock, profile, e, &mut self.counters)
                }
                None => false,
            };
            self.counters.send_errors += u64::from(!ok);
            match self.clients.handle_send(i, ok, processed) {
                SendOutcome::Dropped => {
                    self.sockets.remove(&addr);
                    self.counters.clients_dropped += 1;
                    dropped_any = true;
                    tracing::warn!(target: "emoshift", %addr, "subscriber dropped after repeated send failures");
                    continue;
                }
                SendOutcome::BackingOff(wait) => {
                    self.counters.backoffs += 1;
                    if wait == crate::engine::clients::FIRST_BACKOFF {
                        tracing::warn!(target: "emoshift", %addr, "static target not reachable; retrying at most every second");
                    }
                }
                SendOutcome::Recovered => {
                    tracing::info!(target: "emoshift", %addr, "static target reachable again")
                }
                SendOutcome::Sent | SendOutcome::Failed => {}
            }
            i += 1;
        }
        if !self.clients.is_empty() {
            Stats::record(&mut self.sent_us, processed.elapsed().as_micros() as u64);
        }
        dropped_any
    }
}

/// Sends one datagram; `false` on a send error (a full send buffer is counted as a dropped
/// datagram, not as the subscriber's failure).
fn send_one(sock: &UdpSocket, bytes: &[u8], c: &mut SendCounters) -> bool {
    match sock.send(bytes) {
        Ok(_) => {
            c.datagrams_sent += 1;
            true
        }
        Err(err) if err.kind() == ErrorKind::WouldBlock => {
            c.dropped_send_buffer += 1;
            true
        }
        Err(_) => false,
    }
}

/// Sends one frame in `profile`; `false` on a send error (a full send buffer is counted as a
/// dropped datagram, not as the subscriber's failure).
fn send_profile(sock: &UdpSocket, profile: Profile, e: &Emitted<'_>, c: &mut SendCounters) -> bool {
    let mut ok = true;
    let mut one = |bytes: &[u8]| ok &= send_one(sock, bytes, c);
    match profile {
        Profile::Compact if !e.compact.is_empty() => one(e.compact),
        Profile::Components if !e.components.is_empty() => one(e.components),
        Profile::Compact | Profile::Components => {}
        Profile::FlatSplit => {
            let mut start = 0;
            for &end in e.part_ends {
                one(&e.parts[start..end]);
                start = end;
            }
        }
    }
    ok
}
