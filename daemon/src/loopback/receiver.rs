//! A receiver of the daemon's output: one loopback socket, a task that decodes every datagram
//! and hands it to the caller's sink, which keeps what its caller needs (latencies, positions,
//! component values).

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use protocol::{
    decode_components_into, decode_frame_into, decode_state, messages, Address, Control, FrameBuf,
    FrameHeader, Limits, Profile, State,
};
use tokio::net::UdpSocket;
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;

use super::control::ControlClient;
use crate::serve::net::bind_receiver;

/// How long a receiver collecting until a quiet spell waits for its first datagram.
pub const FIRST_WAIT: Duration = Duration::from_secs(5);

/// What one datagram carried (emoshift sends at most one frame per datagram).
#[derive(Debug)]
pub struct Received<'a> {
    /// When it was read off the socket.
    pub at: Instant,
    /// The frame (compact profile), with its header.
    pub frame: Option<(FrameHeader, &'a FrameBuf)>,
    /// The emotion state that came with it.
    pub state: Option<State<'a>>,
    /// Component values (components profile).
    pub components: Option<&'a [f32]>,
}

/// A loopback socket the daemon sends to.
#[derive(Debug, Clone)]
pub struct Receiver {
    socket: Arc<UdpSocket>,
}

/// A receiver's task: stop it, or let it end after a quiet spell, and take what its sink kept.
#[derive(Debug)]
pub struct Collecting<T> {
    task: JoinHandle<T>,
    stop: CancellationToken,
}

impl Receiver {
    /// A receiver on an ephemeral loopback port, its buffer sized like the daemon's own.
    ///
    /// # Errors
    /// No socket.
    pub fn bind() -> Result<Receiver> {
        let socket =
            bind_receiver(([127, 0, 0, 1], 0).into()).context("cannot open a udp socket")?;
        Ok(Receiver {
            socket: Arc::new(socket),
        })
    }

    /// A receiver subscribed through `/subscribe` with `profile`.
    ///
    /// # Errors
    /// No socket, or the daemon did not confirm.
    pub async fn subscribe(control: &ControlClient, profile: Profile) -> Result<Receiver> {
        let me = Receiver::bind()?;
        let port = me.addr()?.port();
        control
            .confirm(&Control::Subscribe { port, profile })
            .await?;
        Ok(me)
    }

    /// Its address.
    ///
    /// # Errors
    /// The socket has none (never, once bound).
    pub fn addr(&self) -> Result<SocketAddr> {
        Ok(self.socket.local_addr()?)
    }

    /// Decodes every datagram into `sink(&mut kept, ..)` in a task, until stopped or (with
    /// `quiet`) until that long passes without a datagram after the first ([`FIRST_WAIT`] for
    /// the first). Datagrams that do not decode are skipped.
    pub fn collect<T, F>(&self, quiet: Option<Duration>, kept: T, sink: F) -> Collecting<T>
    where
        T: Send + 'static,
        F: FnMut(&mut T, &Received<'_>) + Send + 'static,
    {
        let stop = CancellationToken::new();
        let task = tokio::spawn(receive(
            Arc::clone(&self.socket),
            stop.clone(),
            quiet,
            kept,
            sink,
        ));
        Collecting { task, stop }
    }
}

impl<T> Collecting<T> {
    /// Stops it now and returns what the sink kept.
    ///
    /// # Errors
    /// The sink panicked.
    pub async fn stop(self) -> Result<T> {
        self.stop.cancel();
        self.task.await.context("the receiver panicked")
    }

    /// Waits for the quiet spell that ends it and returns what the sink kept.
    ///
    /// # Errors
    /// The sink panicked.
    pub async fn finish(self) -> Result<T> {
        self.task.await.context("the receiver panicked")
    }
}

async fn receive<T, F>(
    socket: Arc<UdpSocket>,
    stop: CancellationToken,
    quiet: Option<Duration>,
    mut kept: T,
    mut sink: F,
) -> T
where
    F: FnMut(&mut T, &Received<'_>),
{
    let mut buf = vec![0u8; protocol::MAX_UDP_PAYLOAD];
    let mut frame = FrameBuf::with_max_markers(protocol::MAX_FRAME_MARKERS);
    let mut u = vec![0.0f32; 3 * protocol::MAX_FRAME_MARKERS];
    let mut wait = quiet.map(|_| FIRST_WAIT);
    loop {
        let read = async {
            match wait {
                Some(w) => tokio::time::timeout(w, socket.recv(&mut buf)).await.ok(),
                None => Some(socket.recv(&mut buf).await),
            }
        };
        let n = tokio::select! {
            () = stop.cancelled() => break,
            r = read => match r {
                None => break,
                Some(Ok(n)) => n,
                Some(Err(_)) => continue,
            },
        };
        let at = Instant::now();
        wait = quiet;
        let Ok(msgs) = messages(&buf[..n], &Limits::default()) else {
            continue;
        };
        let (mut header, mut state, mut components) = (None, None, None);
        for m in msgs {
            match Address::parse(m.address) {
                Some(Address::Frame) => header = decode_frame_into(m.bytes, &mut frame).ok(),
                Some(Address::State) => state = decode_state(m.bytes).ok(),
                Some(Address::Components) => {
                    components = decode_components_into(m.bytes, &mut u).ok();
                }
                _ => {}
            }
        }
        let got = Received {
            at,
            frame: header.map(|h| (h, &frame)),
            state,
            components: components.map(|k| &u[..k]),
        };
        sink(&mut kept, &got);
    }
    kept
}
