//! The OSC output, a [`Sink`]: each processed frame encoded once per profile its subscribers
//! want ([`encode`]: compact, flat-split, components) and the same bytes sent to every
//! subscriber of that profile, straight from the processing thread. A relay's path is
//! receive → send; handing the bytes to another thread here would add a wake-up (tens of µs on
//! a loaded machine) to every frame, so the daemon's path stays receive → process → send.
//!
//! One connected, non-blocking std socket per subscriber: an ICMP port unreachable comes back
//! as a send error on it, so a vanished client is dropped, or a static target backs off
//! ([`Subscribers::handle_send`]). A full socket send buffer drops that datagram (counted)
//! instead of stalling the thread that processes every stream. Each stream's labels go before
//! its first frame to a subscriber, and once a second ([`streams`]).

pub mod encode;
pub mod streams;

use std::collections::HashMap;
use std::io::ErrorKind;
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use anyhow::Result;
use engine::subscribers::{Change, SendOutcome, Subscriber, Subscribers, FIRST_BACKOFF};
use engine::{Needs, Processed, Sink};
use hdrhistogram::Histogram;
use protocol::{Control, Profile};

use self::encode::{Encoder, Profiles};
use self::streams::Names;
use crate::serve::latency;
use crate::serve::net::connect;

/// How often dynamic subscriptions are checked for expiry.
const EXPIRY_EVERY: Duration = Duration::from_secs(1);

/// Counters of sending.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SendCounters {
    /// Datagrams sent.
    pub datagrams_sent: u64,
    /// Sends that failed.
    pub send_errors: u64,
    /// Subscribers dropped after repeated failures.
    pub clients_dropped: u64,
    /// Times a static target started backing off after repeated failures.
    pub backoffs: u64,
    /// Datagrams not sent because the socket's send buffer was full.
    pub dropped_send_buffer: u64,
    /// Frames that could not be encoded (a stream or target name the wire cannot carry).
    pub encode_errors: u64,
}

/// What the OSC output is set up with.
#[derive(Debug, Clone)]
pub struct OscOutputConfig {
    /// Static subscribers (`--send`, `send = [...]`).
    pub send: Vec<(SocketAddr, Profile)>,
    /// Cap on `/subscribe` subscribers.
    pub max_subscribers: usize,
    /// Failed sends before a subscriber is dropped.
    pub max_send_failures: u32,
    /// How long a `/subscribe` lasts unless renewed.
    pub lease: Duration,
    /// Largest frame, markers.
    pub max_markers: usize,
    /// Blend names sent instead of the defaults (`vmc_names`).
    pub vmc_names: HashMap<String, String>,
}

/// The subscribers, their sockets and the encoded frame, owned by the processing thread.
#[derive(Debug)]
pub struct OscOutput {
    subscribers: Subscribers<Profile>,
    sockets: HashMap<SocketAddr, UdpSocket>,
    encoder: Encoder,
    names: Names,
    /// Counters since the start.
    pub counters: SendCounters,
    /// Processed → sent to the last subscriber, µs, since the last merge.
    pub sent_us: Histogram<u64>,
    next_expiry: Instant,
}

impl OscOutput {
    /// Opens the static subscribers' sockets.
    ///
    /// # Errors
    /// A static subscriber's socket cannot be opened.
    pub fn new(config: &OscOutputConfig) -> Result<OscOutput> {
        let subscribers = Subscribers::new(
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
        Ok(OscOutput {
            subscribers,
            sockets,
            encoder: Encoder::new(config.max_markers),
            names: Names::renamed(config.vmc_names.clone()),
            counters: SendCounters::default(),
            sent_us: latency::histogram(),
            next_expiry: Instant::now() + EXPIRY_EVERY,
        })
    }

    /// The profiles the subscribers want.
    pub fn wanted(&self) -> Profiles {
        self.subscribers
            .iter()
            .fold(Profiles::default(), |m, s| m.with(s.wants))
    }

    /// Subscribers now.
    pub fn len(&self) -> usize {
        self.subscribers.len()
    }

    /// No subscriber.
    pub fn is_empty(&self) -> bool {
        self.subscribers.is_empty()
    }

    /// Every subscriber, for `/status`.
    pub fn subscribers(&self) -> impl Iterator<Item = &Subscriber<Profile>> {
        self.subscribers.iter()
    }

    /// Handles `/subscribe` or `/unsubscribe` from `peer`: the destination is always the
    /// peer's own IP at the port it names (a `/subscribe` from beyond loopback arrives here
    /// only once its cookie was checked), so the daemon never sends to a third party.
    ///
    /// # Errors
    /// The refusal, as the text of the error reply.
    pub fn handle_control(&mut self, peer: SocketAddr, control: &Control) -> Result<(), String> {
        let now = Instant::now();
        let change = match control {
            Control::Subscribe {
                port,
                profile,
                performer,
                ..
            } => {
                let addr = SocketAddr::new(peer.ip(), *port);
                self.subscribers
                    .subscribe(now, addr, *profile, performer.as_deref())
            }
            Control::Unsubscribe { port } => self
                .subscribers
                .unsubscribe(SocketAddr::new(peer.ip(), *port)),
            _ => return Err("not a subscription message".into()),
        };
        match change.map_err(|e| e.to_string())? {
            Change::Added(addr) => match connect(addr) {
                Ok(s) => {
                    self.sockets.insert(addr, s);
                    tracing::info!(target: "emoshift", %addr, "subscriber added");
                    Ok(())
                }
                Err(e) => {
                    let _ = self.subscribers.unsubscribe(addr);
                    Err(format!("cannot open a socket to {addr}: {e}"))
                }
            },
            Change::Removed(addr) => {
                self.sockets.remove(&addr);
                Ok(())
            }
            Change::Renewed(_) => Ok(()),
        }
    }

    /// Drops the dynamic subscriptions whose lease ended (checked once a second).
    pub fn expire(&mut self, now: Instant) {
        if now < self.next_expiry {
            return;
        }
        self.next_expiry = now + EXPIRY_EVERY;
        for addr in self.subscribers.poll_expired(now) {
            self.sockets.remove(&addr);
            tracing::info!(target: "emoshift", %addr, "subscription expired (not renewed)");
        }
    }
}

impl Sink for OscOutput {
    fn needs(&self) -> Needs {
        let wanted = self.wanted();
        let frames = wanted.contains(Profile::Compact) || wanted.contains(Profile::FlatSplit);
        let components = wanted.contains(Profile::Components);
        Needs {
            markers: frames,
            components,
            state: frames,
            labels: !wanted.is_empty(),
            input: false,
            time: frames || components,
        }
    }

    /// Encodes the frame once per wanted profile and sends it to every subscriber of its
    /// stream, with the stream's labels first when they are due.
    fn handle_frame(&mut self, frame: &Processed<'_>) {
        let processed = Instant::now();
        let wanted = self.wanted();
        if wanted.is_empty() {
            return;
        }
        let OscOutput {
            subscribers,
            sockets,
            encoder,
            names,
            counters,
            sent_us,
            ..
        } = self;
        let names = names.of(frame);
        if encoder.encode(wanted, frame, names).is_err() {
            counters.encode_errors += 1;
            return;
        }
        let stream = (frame.identity().id, frame.identity().name.as_str());
        let mut i = 0;
        while let Some(s) = subscribers.get(i) {
            let (addr, profile) = (s.addr, s.wants);
            let plan = subscribers.plan(i, processed, stream, frame.labels_due);
            if !plan.send {
                i += 1;
                continue;
            }
            let labels = plan.labels.then_some(names.labels_msg.as_slice());
            let ok = match sockets.get(&addr) {
                Some(sock) => send_frame(sock, encoder.datagrams(profile), labels, counters),
                None => false,
            };
            counters.send_errors += u64::from(!ok);
            match subscribers.handle_send(i, ok, processed) {
                SendOutcome::Dropped => {
                    sockets.remove(&addr);
                    counters.clients_dropped += 1;
                    tracing::warn!(target: "emoshift", %addr, "subscriber dropped after repeated send failures: its port refuses frames; it may /subscribe again once it listens");
                    continue;
                }
                SendOutcome::BackingOff(wait) => {
                    counters.backoffs += 1;
                    if wait == FIRST_BACKOFF {
                        tracing::warn!(target: "emoshift", %addr, "static target not reachable; retrying at most every second");
                    }
                }
                SendOutcome::Recovered => {
                    tracing::info!(target: "emoshift", %addr, "static target reachable again");
                }
                SendOutcome::Sent | SendOutcome::Failed => {}
            }
            i += 1;
        }
        latency::record(sent_us, processed.elapsed().as_micros() as u64);
    }
}

/// Sends one frame's datagrams, the stream's labels first when given; `false` on a send error.
fn send_frame<'a>(
    sock: &UdpSocket,
    datagrams: impl Iterator<Item = &'a [u8]>,
    labels: Option<&[u8]>,
    c: &mut SendCounters,
) -> bool {
    if !labels.is_none_or(|l| l.is_empty() || send_one(sock, l, c)) {
        return false;
    }
    let mut ok = true;
    for datagram in datagrams {
        ok &= send_one(sock, datagram, c);
    }
    ok
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
