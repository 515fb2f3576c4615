//! The sender task: the same encoded bytes to every subscriber, one connected socket per
//! subscriber (so an ICMP port unreachable comes back as a send error and a vanished client
//! is dropped), buffers returned to the processing thread's pool.

use std::collections::HashMap;
use std::net::{Ipv4Addr, Ipv6Addr, SocketAddr};
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::Result;
use crossbeam_channel::Sender as PoolTx;
use protocol::{Control, Profile};
use tokio::net::UdpSocket;
use tokio::sync::mpsc;

use super::clients::{ClientChange, Clients};
use super::pipeline::Emitted;
use super::server::Answer;
use super::stats::Stats;
use super::Config;

/// A processed frame on its way to the subscribers, in a pooled buffer.
#[derive(Debug)]
pub(crate) struct OutFrame {
    received: Instant,
    processed: Instant,
    compact: Vec<u8>,
    parts: Vec<u8>,
    part_ends: Vec<usize>,
    components: Vec<u8>,
}

impl Default for OutFrame {
    fn default() -> Self {
        let now = Instant::now();
        OutFrame {
            received: now,
            processed: now,
            compact: Vec::with_capacity(protocol::ETHERNET_PAYLOAD),
            parts: Vec::new(),
            part_ends: Vec::new(),
            components: Vec::new(),
        }
    }
}

impl OutFrame {
    /// Copies an emitted frame (capacity reused: no allocation once warm).
    pub(crate) fn fill_from(&mut self, e: &Emitted<'_>, received: Instant) {
        self.received = received;
        self.processed = Instant::now();
        for (dst, src) in [
            (&mut self.compact, e.compact),
            (&mut self.parts, e.parts),
            (&mut self.components, e.components),
        ] {
            dst.clear();
            dst.extend_from_slice(src);
        }
        self.part_ends.clear();
        self.part_ends.extend_from_slice(e.part_ends);
    }

    /// Received → processed, microseconds.
    pub(crate) fn processed_us(&self) -> u64 {
        self.processed.duration_since(self.received).as_micros() as u64
    }
}

/// A `/subscribe` or `/unsubscribe` from the control task.
#[derive(Debug)]
pub(crate) struct ClientCmd {
    pub(crate) peer: SocketAddr,
    pub(crate) control: Control,
    pub(crate) reply: Answer,
}

/// The sender task's state.
#[derive(Debug)]
pub(crate) struct Sender {
    clients: Clients,
    sockets: HashMap<SocketAddr, UdpSocket>,
    stats: Arc<Mutex<Stats>>,
    wanted: Arc<AtomicU8>,
}

/// A socket connected to `addr`, bound on loopback for a loopback peer.
fn connect(addr: SocketAddr) -> std::io::Result<UdpSocket> {
    let local: SocketAddr = match (addr.is_ipv4(), addr.ip().is_loopback()) {
        (true, true) => (Ipv4Addr::LOCALHOST, 0).into(),
        (true, false) => (Ipv4Addr::UNSPECIFIED, 0).into(),
        (false, true) => (Ipv6Addr::LOCALHOST, 0).into(),
        (false, false) => (Ipv6Addr::UNSPECIFIED, 0).into(),
    };
    let s = std::net::UdpSocket::bind(local)?;
    s.connect(addr)?;
    s.set_nonblocking(true)?;
    UdpSocket::from_std(s)
}

impl Sender {
    /// Opens the static subscribers' sockets.
    pub(crate) fn new(
        config: &Config,
        stats: Arc<Mutex<Stats>>,
        wanted: Arc<AtomicU8>,
    ) -> Result<Sender> {
        let clients = Clients::new(
            &config.send,
            config.max_subscribers,
            config.max_send_failures,
        );
        let mut sockets = HashMap::new();
        for &(addr, _) in &config.send {
            let s = connect(addr)
                .map_err(|e| anyhow::anyhow!("opening a socket to subscriber {addr}: {e}"))?;
            sockets.insert(addr, s);
        }
        let sender = Sender {
            clients,
            sockets,
            stats,
            wanted,
        };
        sender.publish();
        Ok(sender)
    }

    fn publish(&self) {
        self.wanted.store(self.clients.wanted(), Ordering::Relaxed);
        if let Ok(mut s) = self.stats.lock() {
            s.clients = self.clients.len() as u64;
        }
    }

    /// Runs until the processing thread closes `frames`.
    pub(crate) async fn run(
        mut self,
        mut frames: mpsc::Receiver<OutFrame>,
        pool: PoolTx<OutFrame>,
        mut commands: mpsc::Receiver<ClientCmd>,
    ) {
        let mut expiry = tokio::time::interval(Duration::from_secs(1));
        loop {
            tokio::select! {
                Some(cmd) = commands.recv() => self.command(cmd),
                f = frames.recv() => match f {
                    Some(f) => {
                        self.send_all(&f).await;
                        let _ = pool.try_send(f);
                    }
                    None => break,
                },
                _ = expiry.tick() => {
                    for addr in self.clients.poll_expired(Instant::now()) {
                        self.sockets.remove(&addr);
                        tracing::info!(%addr, "subscription expired");
                    }
                    self.publish();
                }
            }
        }
    }

    fn command(&mut self, cmd: ClientCmd) {
        let r = self
            .clients
            .handle_control(Instant::now(), cmd.peer, &cmd.control)
            .map_err(|e| e.to_string());
        let r = match r {
            Ok(ClientChange::Added(addr)) => match connect(addr) {
                Ok(s) => {
                    self.sockets.insert(addr, s);
                    tracing::info!(%addr, "subscriber added");
                    Ok(())
                }
                Err(e) => {
                    self.clients
                        .handle_control(
                            Instant::now(),
                            cmd.peer,
                            &Control::Unsubscribe { port: addr.port() },
                        )
                        .ok();
                    Err(format!("cannot open a socket to {addr}: {e}"))
                }
            },
            Ok(ClientChange::Removed(addr)) => {
                self.sockets.remove(&addr);
                Ok(())
            }
            Ok(ClientChange::Renewed(_)) => Ok(()),
            Err(e) => Err(e),
        };
        self.publish();
        let _ = cmd.reply.send(r);
    }

    async fn send_all(&mut self, f: &OutFrame) {
        let (mut sent, mut errors, mut dropped) = (0u64, 0u64, 0u64);
        let mut i = 0;
        loop {
            let next = self.clients.iter().nth(i).map(|s| (s.addr, s.profile));
            let Some((addr, profile)) = next else { break };
            let ok = match self.sockets.get(&addr) {
                Some(sock) => send_profile(sock, profile, f, &mut sent).await,
                None => false,
            };
            errors += u64::from(!ok);
            if self.clients.handle_send(addr, ok) {
                self.sockets.remove(&addr);
                dropped += 1;
                tracing::warn!(%addr, "subscriber dropped after repeated send failures");
            } else {
                i += 1;
            }
        }
        let sent_us = f.processed.elapsed().as_micros() as u64;
        if let Ok(mut s) = self.stats.lock() {
            s.send.datagrams_sent += sent;
            s.send.send_errors += errors;
            s.send.clients_dropped += dropped;
            if !self.clients.is_empty() {
                Stats::record(&mut s.sent_us, sent_us);
            }
        }
        if dropped > 0 {
            self.publish();
        }
    }
}

/// Sends one frame in `profile`; `false` on any send error.
async fn send_profile(sock: &UdpSocket, profile: Profile, f: &OutFrame, sent: &mut u64) -> bool {
    let mut ok = true;
    match profile {
        Profile::Compact | Profile::Components => {
            let bytes = if profile == Profile::Compact {
                &f.compact
            } else {
                &f.components
            };
            if bytes.is_empty() {
                return true;
            }
            ok = sock.send(bytes).await.is_ok();
            *sent += u64::from(ok);
        }
        Profile::FlatSplit => {
            let mut start = 0;
            for &end in &f.part_ends {
                let r = sock.send(&f.parts[start..end]).await.is_ok();
                *sent += u64::from(r);
                ok &= r;
                start = end;
            }
        }
    }
    ok
}
