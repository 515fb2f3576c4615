//! The link's socket and wire helpers: joining a multicast group, receiving on an optional
//! socket, reading a frame's models-changed flag in place.

use std::net::{Ipv4Addr, SocketAddr};

use socket2::{Domain, Protocol, Socket, Type};
use tokio::net::UdpSocket;

use crate::serve::net::RECV_BUFFER_BYTES;

/// A frame's "tracked models changed" flag (frame params bit 1), read in place: the params
/// are the `u16` before the 4-byte end-of-data tag in NatNet 3.x and 4.x.
pub(super) fn models_changed(frame: &[u8]) -> bool {
    frame.len() >= 10 && frame[frame.len() - 6] & 0x02 != 0
}

/// A socket receiving multicast group `group` at `addr`'s port on interface `iface`: bound to
/// the group itself on Unix (so it takes nothing else), the port shared with other clients.
pub(super) fn join_multicast(
    addr: SocketAddr,
    group: Ipv4Addr,
    iface: Ipv4Addr,
) -> std::io::Result<std::net::UdpSocket> {
    let s = Socket::new(Domain::IPV4, Type::DGRAM, Some(Protocol::UDP))?;
    s.set_reuse_address(true)?;
    let _ = s.set_recv_buffer_size(RECV_BUFFER_BYTES);
    let bind: SocketAddr = if cfg!(unix) {
        addr
    } else {
        (Ipv4Addr::UNSPECIFIED, addr.port()).into()
    };
    s.bind(&bind.into())?;
    s.join_multicast_v4(&group, &iface)?;
    Ok(s.into())
}

/// Receives on `socket`, or waits forever without one.
pub(super) async fn recv(socket: Option<&UdpSocket>, buf: &mut [u8]) -> std::io::Result<usize> {
    match socket {
        Some(s) => s.recv(buf).await,
        None => std::future::pending().await,
    }
}

#[cfg(test)]
mod tests;
