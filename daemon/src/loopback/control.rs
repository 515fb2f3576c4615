//! A control client: one socket, one request at a time, each answered or timed out.

use std::net::SocketAddr;
use std::time::Duration;

use anyhow::{bail, Context, Result};
use protocol::{
    decode_reply, encode_control_into, encode_control_signed_into, Control, Reply, StatusValue,
};
use tokio::net::UdpSocket;

/// How long a request waits for its reply.
pub const REPLY_WAIT: Duration = Duration::from_secs(5);

/// Control messages to one daemon, from one loopback socket. Requests allocate: control is
/// rare, and a client shared by reference is simpler to use.
#[derive(Debug)]
pub struct ControlClient {
    socket: UdpSocket,
    to: SocketAddr,
    /// The daemon's shared secret, added to mutating controls.
    secret: Option<String>,
}

impl ControlClient {
    /// A client of the daemon whose control address is `to`.
    ///
    /// # Errors
    /// No loopback socket.
    pub async fn new(to: SocketAddr) -> Result<ControlClient> {
        ControlClient::bind(([127, 0, 0, 1], 0).into(), to).await
    }

    /// A client on `local` (another loopback address stands in for another host).
    ///
    /// # Errors
    /// No socket there.
    pub async fn bind(local: SocketAddr, to: SocketAddr) -> Result<ControlClient> {
        Ok(ControlClient {
            socket: UdpSocket::bind(local)
                .await
                .context("cannot open a udp socket")?,
            to,
            secret: None,
        })
    }

    /// Adds `secret` to every mutating control from now on.
    pub fn with_secret(mut self, secret: &str) -> ControlClient {
        self.secret = Some(secret.to_string());
        self
    }

    /// The daemon's control address.
    pub fn daemon(&self) -> SocketAddr {
        self.to
    }

    /// Its own address.
    ///
    /// # Errors
    /// The socket has none (never, once bound).
    pub fn addr(&self) -> Result<SocketAddr> {
        Ok(self.socket.local_addr()?)
    }

    /// Sends `control` and returns the daemon's reply (an error reply included).
    ///
    /// # Errors
    /// No reply within [`REPLY_WAIT`], or one that does not decode.
    pub async fn request(&self, control: &Control) -> Result<Reply> {
        let mut out = Vec::new();
        match &self.secret {
            Some(secret) if control.is_mutating() => {
                encode_control_signed_into(control, secret, &mut out)
            }
            _ => encode_control_into(control, &mut out),
        };
        self.socket.send_to(&out, self.to).await?;
        let mut buf = vec![0; protocol::MAX_UDP_PAYLOAD];
        loop {
            let (n, from) = tokio::time::timeout(REPLY_WAIT, self.socket.recv_from(&mut buf))
                .await
                .with_context(|| format!("no reply to {control:?} within {REPLY_WAIT:?}"))??;
            // Only the daemon answers here; anything else on the port is not a reply.
            if from == self.to {
                return decode_reply(&buf[..n]).context("a reply that does not decode");
            }
        }
    }

    /// Sends `control` and expects it confirmed.
    ///
    /// # Errors
    /// The daemon refused it (its message), or [`ControlClient::request`] failed.
    pub async fn confirm(&self, control: &Control) -> Result<()> {
        match self.request(control).await? {
            Reply::Confirm(_) => Ok(()),
            Reply::Error { address, message } => bail!("the daemon refused {address}: {message}"),
            other => bail!("unexpected reply to {control:?}: {other:?}"),
        }
    }

    /// The daemon's `/status` counters.
    ///
    /// # Errors
    /// As [`ControlClient::request`], or a reply that is not a status.
    pub async fn status(&self) -> Result<Vec<(String, StatusValue)>> {
        match self.request(&Control::Status).await? {
            Reply::Status(pairs) => Ok(pairs),
            other => bail!("unexpected reply to /status: {other:?}"),
        }
    }
}

/// The counter `name` of a `/status` reply.
pub fn counter(status: &[(String, StatusValue)], name: &str) -> Option<i64> {
    status
        .iter()
        .find(|(k, _)| k == name)
        .and_then(|(_, v)| v.as_int())
}

/// The text `name` of a `/status` reply.
pub fn text<'a>(status: &'a [(String, StatusValue)], name: &str) -> Option<&'a str> {
    status
        .iter()
        .find(|(k, _)| k == name)
        .and_then(|(_, v)| v.as_text())
}
