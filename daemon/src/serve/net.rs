//! Sockets: a receiving socket with a large kernel buffer, and a connected sending socket per
//! subscriber.

use std::net::{Ipv4Addr, Ipv6Addr, SocketAddr};

use socket2::{Domain, Protocol, Socket, Type};

/// Receive buffer asked for (the kernel caps it at `net.core.rmem_max`). A stage sends in
/// bursts (several performers at the same instant, a replay catching up); the usual default
/// of ~208 KiB holds fewer than 100 frames of 109 markers and overflows silently.
pub const RECV_BUFFER_BYTES: usize = 4 << 20;

/// A non-blocking tokio UDP socket bound to `addr` with a [`RECV_BUFFER_BYTES`] receive
/// buffer (or the most the kernel grants: logged when less).
///
/// # Errors
/// The socket cannot be created or bound.
pub fn bind_receiver(addr: SocketAddr) -> std::io::Result<tokio::net::UdpSocket> {
    let s = bind_receiver_std(addr)?;
    s.set_nonblocking(true)?;
    tokio::net::UdpSocket::from_std(s)
}

/// [`bind_receiver`] as a blocking std socket.
///
/// # Errors
/// The socket cannot be created or bound.
pub fn bind_receiver_std(addr: SocketAddr) -> std::io::Result<std::net::UdpSocket> {
    let s = Socket::new(Domain::for_address(addr), Type::DGRAM, Some(Protocol::UDP))?;
    if let Err(e) = s.set_recv_buffer_size(RECV_BUFFER_BYTES) {
        tracing::warn!(target: "emoshift", %addr, error = %e, "cannot enlarge the receive buffer: bursts may be dropped; raise the limit (sysctl net.core.rmem_max)");
    }
    // Linux reports twice the usable size it granted.
    let granted = s.recv_buffer_size().unwrap_or(0) / 2;
    if granted < RECV_BUFFER_BYTES {
        tracing::info!(
            target: "emoshift",
            %addr,
            granted,
            wanted = RECV_BUFFER_BYTES,
            "receive buffer capped by the kernel; raise net.core.rmem_max for bursty sources"
        );
    }
    s.bind(&addr.into())?;
    Ok(s.into())
}

/// A non-blocking std socket connected to `addr` (so an ICMP port unreachable comes back as a
/// send error), bound on loopback for a loopback peer.
///
/// # Errors
/// The socket cannot be bound or connected.
pub fn connect(addr: SocketAddr) -> std::io::Result<std::net::UdpSocket> {
    let local: SocketAddr = match (addr.is_ipv4(), addr.ip().is_loopback()) {
        (true, true) => (Ipv4Addr::LOCALHOST, 0).into(),
        (true, false) => (Ipv4Addr::UNSPECIFIED, 0).into(),
        (false, true) => (Ipv6Addr::LOCALHOST, 0).into(),
        (false, false) => (Ipv6Addr::UNSPECIFIED, 0).into(),
    };
    let s = std::net::UdpSocket::bind(local)?;
    s.connect(addr)?;
    s.set_nonblocking(true)?;
    Ok(s)
}
