//! `emoshift record`: a live source captured to one file for training, the shell around
//! [`take::Take`]. The source is an OSC frame socket (`/mocap/labels`, `/mocap/frame`, and
//! `/mocap/timecode` when sent), or a NatNet server through the same [`Link`] `serve` uses,
//! each markerset a stream. It stops after `--frames` or `--seconds`, or on Ctrl-C, and the
//! file is complete either way. While nothing arrives it says so, once per quiet spell.

pub mod take;

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use protocol::{
    decode_frame_into, decode_labels, decode_timecode, messages, Address, FrameBuf, FrameTime,
    LayoutBook, Limits,
};
use tokio_util::sync::CancellationToken;

use super::natnet::{Link, NatNetConfig, NatNetStatus, Session};
use crate::engine::natnet::NatNetFrames;
use take::{Captured, Incoming, Take};

/// Silence after which `record` says nothing is arriving.
pub const QUIET: Duration = Duration::from_secs(3);

/// Where frames come from.
#[derive(Debug, Clone)]
pub enum Source {
    /// An OSC frame socket.
    Osc(SocketAddr),
    /// A NatNet server.
    NatNet(NatNetConfig),
}

/// What to capture.
#[derive(Debug, Clone)]
pub struct CaptureConfig {
    /// The source.
    pub source: Source,
    /// The file (C3D, TRC or CSV by extension).
    pub out: PathBuf,
    /// Stop after this many frames.
    pub frames: Option<u64>,
    /// Stop after this many seconds of capture.
    pub seconds: Option<f64>,
    /// The stream to record (a NatNet markerset, or `ip:port/layout`); the first seen when
    /// `None`.
    pub performer: Option<String>,
}

/// The take and what the notices need, shared by the receive loop and the status callback.
struct State {
    take: Take,
    last_frame: Option<Instant>,
    quiet_told: bool,
    error: Option<anyhow::Error>,
}

impl State {
    fn done(&self, c: &CaptureConfig) -> bool {
        self.error.is_some()
            || c.frames.is_some_and(|n| self.take.frames() >= n)
            || c.seconds.is_some_and(|s| self.take.seconds() >= s)
    }

    fn push(&mut self, f: &Incoming<'_>) {
        self.last_frame = Some(f.received);
        self.quiet_told = false;
        if self.error.is_none() {
            if let Err(e) = self.take.push(f) {
                self.error = Some(e);
            }
        }
    }

    /// A notice when nothing came for [`QUIET`] (once per quiet spell).
    fn quiet_notice(&mut self, since: Instant, what: impl FnOnce() -> String) -> Option<String> {
        let quiet_from = self.last_frame.unwrap_or(since);
        if self.quiet_told || quiet_from.elapsed() < QUIET {
            return None;
        }
        self.quiet_told = true;
        Some(what())
    }
}

/// Captures until done or `shutdown`; `notice` hears the quiet lines. `None` when no frame of
/// the stream arrived (no file is left).
///
/// # Errors
/// A socket that cannot be bound, or a file that cannot be written.
pub async fn run(
    config: CaptureConfig,
    shutdown: CancellationToken,
    notice: &mut (dyn FnMut(&str) + Send),
) -> Result<Option<Captured>> {
    let state = Mutex::new(State {
        take: Take::new(&config.out, config.performer.clone()),
        last_frame: None,
        quiet_told: false,
        error: None,
    });
    match &config.source {
        Source::Osc(addr) => osc(*addr, &config, &state, &shutdown, notice).await?,
        Source::NatNet(n) => natnet(n.clone(), &config, &state, &shutdown, notice).await?,
    }
    let state = state
        .into_inner()
        .map_err(|_| anyhow::anyhow!("capture state poisoned"))?;
    if let Some(e) = state.error {
        // Close what was written before reporting.
        let _ = state.take.finish();
        return Err(e);
    }
    state.take.finish()
}

async fn osc(
    addr: SocketAddr,
    config: &CaptureConfig,
    state: &Mutex<State>,
    shutdown: &CancellationToken,
    notice: &mut (dyn FnMut(&str) + Send),
) -> Result<()> {
    let socket = super::net::bind_receiver(addr)
        .with_context(|| format!("binding the frame socket {addr}"))?;
    let bound = socket.local_addr()?;
    tracing::info!(target: "emoshift", listen = %bound, "record: waiting for frames");
    let mut buf = vec![0u8; protocol::MAX_UDP_PAYLOAD + 1];
    let mut layouts = LayoutBook::new(64);
    let mut frame = FrameBuf::new();
    let started = Instant::now();
    let mut tick = tokio::time::interval(Duration::from_millis(250));
    loop {
        let (n, peer) = tokio::select! {
            () = shutdown.cancelled() => return Ok(()),
            _ = tick.tick() => {
                let mut s = lock(state);
                let line = s.quiet_notice(started, || format!(
                    "nothing has arrived on {bound} for {} s: is the source sending \
                     /mocap/labels and /mocap/frame here?", QUIET.as_secs()));
                drop(s);
                if let Some(line) = line { notice(&line) }
                continue;
            }
            r = socket.recv_from(&mut buf) => match r { Ok(r) => r, Err(_) => continue },
        };
        let Ok(msgs) = messages(&buf[..n], &Limits::default()) else {
            continue;
        };
        let mut time = FrameTime::default();
        for m in msgs.clone() {
            if Address::parse(m.address) == Some(Address::Timecode) {
                time = decode_timecode(m.bytes).unwrap_or_default();
            }
        }
        for m in msgs {
            match Address::parse(m.address) {
                Some(Address::Labels) => {
                    if let Ok(l) = decode_labels(m.bytes) {
                        layouts.handle_labels(&peer, l);
                    }
                }
                Some(Address::Frame) => {
                    let Ok(header) = decode_frame_into(m.bytes, &mut frame) else {
                        continue;
                    };
                    let Some(labels) = layouts.layout_for(&peer, header.marker_count) else {
                        continue;
                    };
                    let stream = format!("{peer}/{}", labels.layout_id);
                    lock(state).push(&Incoming {
                        stream: &stream,
                        labels: &labels.names,
                        frame: &frame,
                        header,
                        timecode: time.timecode,
                        announced_rate_hz: None,
                        received: Instant::now(),
                    });
                }
                _ => {}
            }
        }
        if lock(state).done(config) {
            return Ok(());
        }
    }
}

async fn natnet(
    n: NatNetConfig,
    config: &CaptureConfig,
    state: &Mutex<State>,
    shutdown: &CancellationToken,
    notice: &mut (dyn FnMut(&str) + Send),
) -> Result<()> {
    let server = n.server;
    let link = Link::open(n)?;
    let stop = shutdown.child_token();
    let mut frames = NatNetFrames::new(protocol::MAX_FRAME_MARKERS);
    let mut buf = FrameBuf::new();
    let started = Instant::now();
    let mut on_frame = |bytes: &[u8], received: Instant, session: &Arc<Session>| {
        let layout = &session.layout;
        if let Err(e) = frames.decode(bytes, layout) {
            tracing::debug!(target: "emoshift", error = %e, "record: a NatNet frame did not decode");
            return;
        }
        let time = frames.time(layout);
        let mut s = lock(state);
        for set in &layout.markersets {
            let Some(header) = frames.markerset_into(set, layout, &mut buf) else {
                continue;
            };
            s.push(&Incoming {
                stream: &set.name,
                labels: &set.labels,
                frame: &buf,
                header,
                timecode: time.timecode,
                announced_rate_hz: session.announced_rate_hz,
                received,
            });
        }
        if s.done(config) {
            stop.cancel();
        }
    };
    let mut on_status = |st: &NatNetStatus| {
        let mut s = lock(state);
        let line = s.quiet_notice(started, || natnet_quiet(server, st));
        drop(s);
        if let Some(line) = line {
            notice(&line);
        }
    };
    link.run(stop.clone(), &mut on_frame, &mut on_status).await
}

/// Why nothing arrives from a NatNet server, as far as the session can tell.
fn natnet_quiet(server: SocketAddr, st: &NatNetStatus) -> String {
    let secs = QUIET.as_secs();
    if !st.connected {
        return format!(
            "no answer from a NatNet server at {server} for {secs} s: is Motive running \
             there with streaming enabled (Settings > Streaming > NatNet: Enable), and its \
             command port {}?",
            server.port()
        );
    }
    format!(
        "connected to {} at {server}, but no frames for {secs} s on {}: is Motive live (or \
         playing a take), with asset markers streamed? For unicast, is --natnet-data this \
         host's address?",
        st.server_name, st.data
    )
}

fn lock(state: &Mutex<State>) -> std::sync::MutexGuard<'_, State> {
    state
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}
