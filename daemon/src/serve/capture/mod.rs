//! `emoshift record`: a live source captured to one file for training (a "capture"; the
//! service's `/record/start` is a "session recording"), the shell around [`take::Take`]. The
//! source is the same as `serve`'s ([`super::sources`]): an OSC frame socket
//! (`/mocap/labels`, `/mocap/frame`, and `/mocap/timecode` when sent) or a NatNet server, each
//! markerset a stream. It stops after `--frames` or `--seconds`, or on Ctrl-C, and the file is
//! complete either way. While nothing arrives it says so, once per quiet spell.

pub mod take;

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::AtomicU64;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use engine::SourceFrame;
use tokio_util::sync::CancellationToken;

use super::allow::AllowList;
use super::sources::natnet::{Link, NatNetConfig, NatNetStatus};
use super::sources::osc::{OscIntake, OscSource};
use super::sources::qtm::{QtmConfig, QtmStatus};
use super::sources::{Answer, Arrival, InputCounters};
use take::{Captured, Incoming, Take};

/// Silence after which `record` says nothing is arriving.
pub const QUIET: Duration = Duration::from_secs(3);

/// What the capture tells its caller: a line to print, or how far it is (on every status
/// tick, a few times a second, once a stream is being recorded).
#[derive(Debug)]
pub enum Notice<'a> {
    /// A line for the user (nothing arriving, a performer not found).
    Line(&'a str),
    /// The take so far.
    Progress(&'a CaptureProgress),
}

/// The take so far, for a progress display.
#[derive(Debug, Clone, PartialEq)]
pub struct CaptureProgress {
    /// The stream recorded.
    pub stream: String,
    /// Frames taken, gaps included.
    pub frames: u64,
    /// Frames written as gaps.
    pub gaps: u64,
    /// Seconds of capture.
    pub seconds: f64,
    /// The rate measured so far, Hz.
    pub rate_hz: Option<f64>,
}

/// The callback that hears [`Notice`]s.
pub type OnNotice<'a> = dyn FnMut(Notice<'_>) + Send + 'a;

/// Where frames come from.
#[derive(Debug, Clone)]
pub enum Source {
    /// An OSC frame socket.
    Osc(SocketAddr),
    /// A NatNet server.
    NatNet(NatNetConfig),
    /// Qualisys QTM.
    Qtm(QtmConfig),
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
    quiet: Quiet,
    /// Whether the missing `--performer` was told.
    wrong_told: bool,
    error: Option<anyhow::Error>,
}

impl State {
    fn done(&self, c: &CaptureConfig) -> bool {
        self.error.is_some()
            || c.frames.is_some_and(|n| self.take.frames() >= n)
            || c.seconds.is_some_and(|s| self.take.seconds() >= s)
    }

    fn push(&mut self, f: &Incoming<'_>) {
        self.quiet.heard(f.received);
        if self.error.is_none() {
            if let Err(e) = self.take.push(f) {
                self.error = Some(e);
            }
        }
    }

    /// The take so far, once a stream is being recorded.
    fn progress(&self) -> Option<CaptureProgress> {
        Some(CaptureProgress {
            stream: self.take.stream()?.to_string(),
            frames: self.take.frames(),
            gaps: self.take.gaps(),
            seconds: self.take.seconds(),
            rate_hz: self.take.measured(),
        })
    }

    /// What to tell on a status tick: the quiet or wrong-performer line, then the progress.
    fn tick(&mut self, since: Instant, what: impl FnOnce() -> String, notice: &mut OnNotice<'_>) {
        if let Some(line) = self.quiet_notice(since, what) {
            notice(Notice::Line(&line));
        }
        if let Some(p) = self.progress() {
            notice(Notice::Progress(&p));
        }
    }

    /// A notice when nothing came for [`QUIET`] (once per quiet spell), or when the stream
    /// asked for is not among those that came (once).
    fn quiet_notice(&mut self, since: Instant, what: impl FnOnce() -> String) -> Option<String> {
        if !self.wrong_told {
            if let Some(line) = wrong_performer(&self.take) {
                self.wrong_told = true;
                return Some(line);
            }
        }
        self.quiet.notice(since, what)
    }
}

/// When a frame last came, for the notice that nothing arrives (shared by a source's sink and
/// its quiet timer).
#[derive(Debug, Default)]
pub struct Quiet {
    last_frame: Option<Instant>,
    told: bool,
}

impl Quiet {
    /// A frame arrived at `at`.
    pub fn heard(&mut self, at: Instant) {
        self.last_frame = Some(at);
        self.told = false;
    }

    /// A notice when nothing came for [`QUIET`] (once per quiet spell).
    fn notice(&mut self, since: Instant, what: impl FnOnce() -> String) -> Option<String> {
        let quiet_from = self.last_frame.unwrap_or(since);
        if self.told || quiet_from.elapsed() < QUIET {
            return None;
        }
        self.told = true;
        Some(what())
    }
}

/// The stream name a frame is recorded under: its performer, else `ip:port/layout`.
pub fn stream_name(frame: &SourceFrame<'_>) -> String {
    match frame.performer {
        Some(name) => name.to_string(),
        None => format!("{}/{}", frame.key.source, frame.key.layout_id),
    }
}

/// One frame as [`Take::push`] takes it.
pub fn incoming<'a>(
    frame: &'a SourceFrame<'_>,
    arrival: &Arrival,
    stream: &'a str,
) -> Incoming<'a> {
    Incoming {
        stream,
        labels: frame.labels,
        frame: frame.frame,
        header: frame.frame.header(),
        timecode: frame.time.timecode,
        announced_rate_hz: arrival.announced_rate_hz,
        received: arrival.received,
    }
}

/// Hears a source's status ticks (a few a second) with the text that says why nothing arrives.
type OnTick<'a> = dyn FnMut(&dyn Fn() -> String) + Send + 'a;

/// Captures until done or `shutdown`; `notice` hears the quiet lines and the progress. `None`
/// when no frame of the stream arrived (no file is left).
///
/// # Errors
/// A socket that cannot be bound, or a file that cannot be written.
pub async fn run(
    config: CaptureConfig,
    shutdown: CancellationToken,
    notice: &mut OnNotice<'_>,
) -> Result<Option<Captured>> {
    let state = Mutex::new(State {
        take: Take::new(&config.out, config.performer.clone()),
        quiet: Quiet::default(),
        wrong_told: false,
        error: None,
    });
    let stop = shutdown.child_token();
    let mut sink = |frame: &SourceFrame<'_>, arrival: &Arrival| {
        let stream = stream_name(frame);
        let mut s = lock(&state);
        s.push(&incoming(frame, arrival, &stream));
        if s.done(&config) {
            stop.cancel();
        }
    };
    let started = Instant::now();
    let mut on_tick = |what: &dyn Fn() -> String| lock(&state).tick(started, what, notice);
    drive(&config.source, &stop, &mut sink, &mut on_tick).await?;
    let state = state
        .into_inner()
        .map_err(|_| anyhow::anyhow!("capture state poisoned"))?;
    if let Some(e) = state.error {
        // Close what was written before reporting.
        let _ = state.take.finish();
        return Err(e);
    }
    if let Some(line) = wrong_performer(&state.take) {
        anyhow::bail!("nothing written to {}: {line}", config.out.display());
    }
    state.take.finish()
}

/// "no marker set 'face'; the server has: Face", when the `--performer` asked for names none
/// of the streams that came.
fn wrong_performer(take: &Take) -> Option<String> {
    let (wanted, others) = take.wanted_missing()?;
    Some(format!(
        "no marker set '{wanted}'; the server has: {} (names are case-sensitive: pass one of \
         them to --performer)",
        others.join(", ")
    ))
}

/// The source until `stop`, each frame to `sink`, with a notice (to `notice`) while nothing
/// comes (`sink` tells `quiet` of each frame): for a caller with its own takes (`session`).
///
/// # Errors
/// A socket that cannot be bound.
pub async fn listen(
    source: &Source,
    quiet: &Mutex<Quiet>,
    stop: &CancellationToken,
    sink: &mut (dyn FnMut(&SourceFrame<'_>, &Arrival) + Send),
    notice: &mut (dyn FnMut(&str) + Send),
) -> Result<()> {
    let started = Instant::now();
    let mut on_tick = |what: &dyn Fn() -> String| {
        let line = quiet
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .notice(started, what);
        if let Some(line) = line {
            notice(&line);
        }
    };
    drive(source, stop, sink, &mut on_tick).await
}

/// The source until `stop`, each frame to `sink`, `on_tick` a few times a second.
async fn drive(
    source: &Source,
    stop: &CancellationToken,
    sink: &mut (dyn FnMut(&SourceFrame<'_>, &Arrival) + Send),
    on_tick: &mut OnTick<'_>,
) -> Result<()> {
    match source {
        Source::Osc(addr) => osc(*addr, stop, sink, on_tick).await,
        Source::NatNet(n) => natnet(n.clone(), stop, sink, on_tick).await,
        Source::Qtm(q) => qtm(q.clone(), stop, sink, on_tick).await,
    }
}

/// The OSC source on `addr` until `stop`, ticking every 250 ms.
async fn osc(
    addr: SocketAddr,
    stop: &CancellationToken,
    sink: &mut (dyn FnMut(&SourceFrame<'_>, &Arrival) + Send),
    on_tick: &mut OnTick<'_>,
) -> Result<()> {
    let socket = super::net::bind_receiver(addr)
        .with_context(|| format!("binding the frame socket {addr}"))?;
    let bound = socket.local_addr()?;
    tracing::info!(target: "emoshift", listen = %bound, "record: waiting for frames");
    let source = OscSource {
        socket,
        intake: OscIntake::new(
            (AllowList::anyone(), Arc::new(AtomicU64::new(0))),
            Arc::new(Answer::new(None)),
            Arc::new(InputCounters::named("osc")),
            protocol::MAX_FRAME_MARKERS,
        ),
    };
    let quiet = async {
        let mut tick = tokio::time::interval(Duration::from_millis(250));
        loop {
            tokio::select! {
                () = stop.cancelled() => return,
                _ = tick.tick() => {}
            }
            let quiet = || {
                format!(
                    "nothing has arrived on {bound} for {} s: is the source sending \
                     /mocap/labels and /mocap/frame here?",
                    QUIET.as_secs()
                )
            };
            on_tick(&quiet);
        }
    };
    tokio::join!(super::sources::osc::run(source, sink, stop.clone()), quiet);
    Ok(())
}

/// The NatNet source until `stop`, ticking on each of the link's status reports.
async fn natnet(
    n: NatNetConfig,
    stop: &CancellationToken,
    sink: &mut (dyn FnMut(&SourceFrame<'_>, &Arrival) + Send),
    on_tick: &mut OnTick<'_>,
) -> Result<()> {
    let server = n.server;
    let link = Link::open(n, Arc::new(InputCounters::named("natnet")))?;
    let mut on_status = |st: &NatNetStatus| on_tick(&|| natnet_quiet(server, st));
    link.run(stop.clone(), sink, &mut on_status).await
}

/// The QTM source until `stop`, with a quiet notice while nothing comes.
async fn qtm(
    q: QtmConfig,
    stop: &CancellationToken,
    sink: &mut (dyn FnMut(&SourceFrame<'_>, &Arrival) + Send),
    on_tick: &mut OnTick<'_>,
) -> Result<()> {
    let mut on_status = |st: &QtmStatus| on_tick(&|| qtm_quiet(st));
    let counters = Arc::new(InputCounters::named("qtm"));
    super::sources::qtm::run(q, counters, stop.clone(), sink, &mut on_status).await
}

/// Why nothing arrives from QTM, as far as the session can tell.
fn qtm_quiet(st: &QtmStatus) -> String {
    let secs = QUIET.as_secs();
    if st.connected {
        format!(
            "connected to QTM at {}, but no frames for {secs} s: is a measurement running (or \
             RT from file), with 3D tracking on?",
            st.server
        )
    } else {
        format!(
            "no session with QTM at {} for {secs} s: is QTM running there with real-time \
             output on (Project Options > Real-Time Output)?",
            st.server
        )
    }
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
