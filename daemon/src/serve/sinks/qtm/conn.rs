//! The QTM server's connections: the accepting loop (allow-list, client cap), one task per
//! client cutting its byte stream into packets ([`Framer`], [`MAX_PACKET`] at most) for the
//! [`Hub`], and the discovery answer. Bad input is counted, bounded and logged once per kind:
//! an oversized or malformed packet closes its connection (the stream cannot be resynchronised),
//! half a packet left stalling for [`STALL_TIMEOUT`] closes it too.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use protocol::qtm::{
    decode_discover, encode_discover_reply_into, encode_text_into, Framer, PacketType,
};
use tokio::io::AsyncReadExt;
use tokio::net::{TcpListener, TcpStream, UdpSocket};
use tokio_util::sync::CancellationToken;
use tracing::Instrument;

use super::hub::{After, Hub};
use super::outbox::Outbox;
use crate::serve::allow::AllowList;

/// The largest packet a client may send (commands are short; QTM's own settings XML is the
/// largest thing a client sends, and emoshift refuses it).
pub const MAX_PACKET: usize = 64 * 1024;
/// Half a packet waits this long for the rest.
pub const STALL_TIMEOUT: Duration = Duration::from_secs(5);
/// How often a connection checks that the frame side has not dropped its client.
const ALIVE_EVERY: Duration = Duration::from_secs(1);

/// Who may connect, and how many at once.
#[derive(Debug, Clone)]
pub struct Limits {
    /// Clients at most.
    pub max_clients: usize,
    /// Who may connect.
    pub allow: AllowList,
}

/// Accepts clients until `shutdown`.
pub async fn accept(
    listener: TcpListener,
    hub: Arc<Mutex<Hub>>,
    limits: Limits,
    shutdown: CancellationToken,
) {
    let mut next_id = 0u64;
    loop {
        let (stream, peer) = tokio::select! {
            () = shutdown.cancelled() => break,
            r = listener.accept() => match r {
                Ok(a) => a,
                Err(_) => continue,
            },
        };
        let Ok(mut h) = hub.lock() else { break };
        if !limits.allow.allows(peer.ip()) {
            h.counters.not_allowed += 1;
            if h.counters.not_allowed == 1 {
                tracing::warn!(%peer, "QTM client refused: not on control_allow (add its network there)");
            }
            continue;
        }
        if h.clients.len() >= limits.max_clients {
            h.counters.refused_full += 1;
            if h.counters.refused_full == 1 {
                tracing::warn!(%peer, max = limits.max_clients,
                    "QTM client refused: too many clients (raise qtm_server_max_clients)");
            }
            let mut out = Vec::new();
            let text = "Too many clients: emoshift's QTM server is full, try again later";
            encode_text_into(PacketType::Error, text, &mut out);
            let _ = stream.try_write(&out);
            continue;
        }
        let Some((reader, writer)) = split(stream) else {
            continue;
        };
        next_id += 1;
        if h.add(next_id, peer, Outbox::new(Box::new(writer))) == After::Close {
            continue;
        }
        tracing::info!(%peer, clients = h.clients.len(), "QTM client connected");
        drop(h);
        let task = client(reader, next_id, Arc::clone(&hub), shutdown.clone());
        tokio::spawn(task.instrument(tracing::info_span!("qtm_client", %peer)));
    }
}

/// The reading half for the runtime, the writing half (the same socket, non-blocking) for the
/// hub.
fn split(stream: TcpStream) -> Option<(TcpStream, std::net::TcpStream)> {
    let std = stream.into_std().ok()?;
    std.set_nodelay(true).ok()?;
    let writer = std.try_clone().ok()?;
    let reader = TcpStream::from_std(std).ok()?;
    Some((reader, writer))
}

/// Reads one client's packets until it leaves, misbehaves or `shutdown`.
async fn client(mut reader: TcpStream, id: u64, hub: Arc<Mutex<Hub>>, shutdown: CancellationToken) {
    let mut framer = Framer::new(MAX_PACKET);
    let mut alive = tokio::time::interval(ALIVE_EVERY);
    // Set when half a packet arrives; the rest must follow by then (a trickle does not reset it).
    let mut stall_deadline: Option<tokio::time::Instant> = None;
    let why = 'conn: loop {
        stall_deadline = match (framer.pending() > 0, stall_deadline) {
            (false, _) => None,
            (true, None) => Some(tokio::time::Instant::now() + STALL_TIMEOUT),
            (true, d) => d,
        };
        let stall = tokio::time::sleep_until(stall_deadline.unwrap_or_else(far_future));
        let n = tokio::select! {
            () = shutdown.cancelled() => break 'conn "shutdown",
            _ = alive.tick() => {
                let gone = hub.lock().map_or(true, |h| !h.clients.iter().any(|c| c.id == id));
                if gone { break 'conn "dropped: not reading" }
                continue;
            }
            () = stall, if stall_deadline.is_some() => {
                if let Ok(mut h) = hub.lock() {
                    h.counters.stalled += 1;
                    if h.counters.stalled == 1 {
                        tracing::warn!("QTM client closed: half a packet stalled");
                    }
                }
                break 'conn "stalled";
            }
            r = reader.read(framer.buffer()) => r,
        };
        match n {
            Ok(0) | Err(_) => break 'conn "closed by the client",
            Ok(n) => framer.filled(n),
        }
        if let Some(why) = drain(&mut framer, &hub, id) {
            break 'conn why;
        }
    };
    if let Ok(mut h) = hub.lock() {
        h.remove(id);
    }
    tracing::info!(why, "QTM client left");
}

/// Hands every whole packet received to the hub; why the connection ends, if it does.
fn drain(framer: &mut Framer, hub: &Mutex<Hub>, id: u64) -> Option<&'static str> {
    loop {
        let packet = match framer.next_packet() {
            Ok(None) => return None,
            Ok(Some(p)) => p,
            Err(e) => {
                if let Ok(mut h) = hub.lock() {
                    h.counters.bad_packets += 1;
                    if h.counters.bad_packets == 1 {
                        tracing::warn!(error = %e, "QTM client closed: bad packet");
                    }
                }
                return Some("bad packet");
            }
        };
        let Ok(mut h) = hub.lock() else {
            return Some("poisoned");
        };
        let after = match (packet.kind, packet.text()) {
            (PacketType::Command, Ok(text)) => h.handle_command(id, text),
            (kind, _) => h.handle_other(id, kind),
        };
        if after == After::Close {
            return Some("disconnect");
        }
    }
}

/// A deadline that never comes.
fn far_future() -> tokio::time::Instant {
    tokio::time::Instant::now() + Duration::from_secs(86_400 * 365)
}

/// Answers discovery requests from allowed hosts with emoshift's name and the base port of the
/// RT `port`: QTM answers 22222 for its little-endian port 22223, and the C++ SDK's `Connect`
/// (under QTM Connect for Unreal, Unity, MotionBuilder) adds 1 to the base port it is given.
pub async fn discovery(
    socket: UdpSocket,
    port: u16,
    (hub, allow): (Arc<Mutex<Hub>>, AllowList),
    shutdown: CancellationToken,
) {
    let mut buf = [0u8; 64];
    let mut out = Vec::with_capacity(64);
    let info = concat!("emoshift ", env!("CARGO_PKG_VERSION"));
    loop {
        let (n, peer) = tokio::select! {
            () = shutdown.cancelled() => break,
            r = socket.recv_from(&mut buf) => match r {
                Ok(r) => r,
                Err(_) => continue,
            },
        };
        if !allow.allows(peer.ip()) {
            continue;
        }
        let Ok(reply_port) = decode_discover(&buf[..n]) else {
            continue;
        };
        encode_discover_reply_into(info, port.saturating_sub(1), &mut out);
        if socket.send_to(&out, (peer.ip(), reply_port)).await.is_ok() {
            if let Ok(mut h) = hub.lock() {
                h.counters.discoveries += 1;
            }
        }
    }
}
