//! A receiver of the daemon's output: one loopback socket, a task that decodes every datagram
//! and hands it to the caller's sink, which keeps what its caller needs (latencies, positions,
//! component values).

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use protocol::{
    decode_components_into, decode_frame_into, decode_labels, decode_state, decode_stream,
    messages, Address, Control, FrameBuf, FrameHeader, Labels, Limits, Profile, State,
};
use tokio::net::UdpSocket;
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;

use super::control::ControlClient;
use crate::serve::net::bind_receiver;

/// How long a receiver collecting until a quiet spell waits for its first datagram.
pub const FIRST_WAIT: Duration = Duration::from_secs(5);

/// How often a subscribed receiver renews its lease (the daemon's default lease is 10 s).
pub const RENEW_EVERY: Duration = Duration::from_secs(3);

/// What one datagram carried (emoshift sends at most one frame per datagram).
#[derive(Debug)]
pub struct Received<'a> {
    /// When it was read off the socket.
    pub at: Instant,
    /// The stream it belongs to: id and name.
    pub stream: Option<(i32, &'a str)>,
    /// A stream's labels (layout id = stream id).
    pub labels: Option<Labels>,
    /// The frame (compact profile), with its header.
    pub frame: Option<(FrameHeader, &'a FrameBuf)>,
    /// The emotion state that came with it.
    pub state: Option<State<'a>>,
    /// Component values (components profile).
    pub components: Option<&'a [f32]>,
    /// The source's timecode and clock, when the frame came with them.
    pub time: Option<protocol::FrameTime>,
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
        Receiver::bind_at(([127, 0, 0, 1], 0).into())
    }

    /// A receiver on `addr` (a loopback address other than 127.0.0.1 stands in for another
    /// host; a fixed port for a static target).
    ///
    /// # Errors
    /// No socket there.
    pub fn bind_at(addr: SocketAddr) -> Result<Receiver> {
        let socket = bind_receiver(addr).context("cannot open a udp socket")?;
        Ok(Receiver {
            socket: Arc::new(socket),
        })
    }

    /// A receiver subscribed through `/subscribe` with `profile`, renewing its lease every
    /// [`RENEW_EVERY`] for as long as a clone of it lives.
    ///
    /// # Errors
    /// No socket, or the daemon did not confirm.
    pub async fn subscribe(control: &ControlClient, profile: Profile) -> Result<Receiver> {
        Receiver::subscribe_to(control, profile, None).await
    }

    /// [`Receiver::subscribe`] to one performer's stream only (`None`: every stream).
    ///
    /// # Errors
    /// No socket, or the daemon did not confirm.
    pub async fn subscribe_to(
        control: &ControlClient,
        profile: Profile,
        performer: Option<&str>,
    ) -> Result<Receiver> {
        let me = Receiver::bind()?;
        let subscribe = Control::Subscribe {
            port: me.addr()?.port(),
            profile,
            performer: performer.map(String::from),
            cookie: None,
        };
        control.confirm(&subscribe).await?;
        let (alive, daemon) = (Arc::downgrade(&me.socket), control.daemon());
        tokio::spawn(async move {
            let Ok(renewer) = ControlClient::new(daemon).await else {
                return;
            };
            loop {
                tokio::time::sleep(RENEW_EVERY).await;
                if alive.upgrade().is_none() || renewer.request(&subscribe).await.is_err() {
                    return;
                }
            }
        });
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
        wait = quiet;
        let Some(got) = decode(&buf[..n], Instant::now(), &mut frame, &mut u) else {
            continue;
        };
        sink(&mut kept, &got);
    }
    kept
}

/// What one datagram carried; `None` when it does not scan.
fn decode<'a>(
    datagram: &'a [u8],
    at: Instant,
    frame: &'a mut FrameBuf,
    u: &'a mut [f32],
) -> Option<Received<'a>> {
    let msgs = messages(datagram, &Limits::default()).ok()?;
    let (mut header, mut state, mut components) = (None, None, None);
    let (mut stream, mut labels, mut time) = (None, None, None);
    for m in msgs {
        match Address::parse(m.address) {
            Some(Address::Stream) => stream = decode_stream(m.bytes).ok(),
            Some(Address::Labels) => labels = decode_labels(m.bytes).ok(),
            Some(Address::Frame) => header = decode_frame_into(m.bytes, frame).ok(),
            Some(Address::State) => state = decode_state(m.bytes).ok(),
            Some(Address::Timecode) => time = protocol::decode_timecode(m.bytes).ok(),
            Some(Address::Components) => components = decode_components_into(m.bytes, u).ok(),
            _ => {}
        }
    }
    Some(Received {
        at,
        stream,
        labels,
        frame: header.map(|h| (h, &*frame)),
        state,
        components: components.map(|k| &u[..k]),
        time,
    })
}
