//! The QTM source: emoshift as a client of Qualisys QTM's RT protocol (`--qtm HOST[:PORT]`,
//! config `qtm`), for `serve` and `record`.
//!
//! One TCP connection, steps logged: welcome, `Version 1.25` (agreed or refused), `GetParameters
//! General 3D` (frequency, labels: the streams, [`frames`]), `StreamFrames AllFrames 3D
//! Timecode` (every frame over the same connection). Events are followed: parameters changed
//! (camera settings), a capture or RT-from-file started or stopped, or a frame whose marker
//! count disagrees with the labels: the parameters are read again. QTM shutting down, the
//! connection closing or garbage (a packet over [`MAX_PACKET`], an unknown type): reconnect
//! with back-off (250 ms doubling to 5 s), as the NatNet source does. No password is ever
//! asked: streaming needs no control of QTM. `/status` carries `qtm/*`.

pub mod config;
pub mod frames;

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use protocol::qtm::{
    decode_parameters, encode_text_into, Event, Framer, Packet, PacketType, MAX_VERSION_TEXT,
};
use protocol::{FrameBuf, StatusValue};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::tcp::OwnedWriteHalf;
use tokio::net::TcpStream;
use tokio_util::sync::CancellationToken;

pub use self::config::{QtmConfig, RawQtm};
use self::frames::{Outcome, QtmFrames};
use super::{Arrival, FrameSink, InputCounters};

/// The largest packet taken from QTM (parameters of thousands of labels fit; a larger one is
/// garbage and the connection is made again).
pub const MAX_PACKET: usize = 4 * 1024 * 1024;
/// The first wait before reconnecting; it doubles up to [`MAX_BACKOFF`].
const FIRST_BACKOFF: Duration = Duration::from_millis(250);
/// The longest wait before reconnecting.
const MAX_BACKOFF: Duration = Duration::from_secs(5);
/// How long a connect may take.
const CONNECT_TIMEOUT: Duration = Duration::from_secs(3);
/// How often the owner hears the status even when nothing happens.
const STATUS_EVERY: Duration = Duration::from_secs(1);
/// What is asked for.
const GET_PARAMETERS: &str = "GetParameters General 3D";
const STREAM: &str = "StreamFrames AllFrames 3D Timecode";

/// The source's state, for `/status` (`qtm/*`) and `record`'s notices.
#[derive(Debug, Clone)]
pub struct QtmStatus {
    /// QTM's address.
    pub server: SocketAddr,
    /// Whether a connection is up and the version agreed.
    pub connected: bool,
    /// Connections made again after one ended.
    pub reconnects: u64,
    /// Frames taken.
    pub frames: u64,
    /// Labels in the parameters.
    pub labels: usize,
    /// The streams, by name.
    pub streams: String,
    /// Packets that did not decode, and frames whose marker count disagreed with the labels.
    pub bad_packets: u64,
    /// Error packets QTM sent.
    pub qtm_errors: u64,
    /// The last event QTM sent.
    pub last_event: String,
}

impl QtmStatus {
    /// `/status` pairs: `qtm/...`.
    pub fn pairs(&self) -> Vec<(String, StatusValue)> {
        let int = |k: &str, v: u64| {
            (
                format!("qtm/{k}"),
                StatusValue::Int(i64::try_from(v).unwrap_or(i64::MAX)),
            )
        };
        let text = |k: &str, v: String| (format!("qtm/{k}"), StatusValue::Text(v));
        vec![
            text("server", self.server.to_string()),
            int("connected", u64::from(self.connected)),
            int("reconnects", self.reconnects),
            int("frames", self.frames),
            int("labels", self.labels as u64),
            text("streams", self.streams.clone()),
            int("bad_packets", self.bad_packets),
            int("qtm_errors", self.qtm_errors),
            text("last_event", self.last_event.clone()),
        ]
    }
}

/// How a session ended.
enum Ended {
    Shutdown,
    Lost(&'static str),
}

/// Takes frames from QTM until `shutdown`, reconnecting when the connection ends; each
/// stream's frames to `sink`, the status to `on_status` at each step.
///
/// # Errors
/// None today (every failure reconnects); the signature keeps the sources' shape.
pub async fn run(
    config: QtmConfig,
    counters: Arc<InputCounters>,
    shutdown: CancellationToken,
    sink: &mut FrameSink<'_>,
    on_status: &mut (dyn FnMut(&QtmStatus) + Send),
) -> Result<()> {
    let mut status = QtmStatus {
        server: config.server,
        connected: false,
        reconnects: 0,
        frames: 0,
        labels: 0,
        streams: String::new(),
        bad_packets: 0,
        qtm_errors: 0,
        last_event: String::new(),
    };
    let mut backoff = FIRST_BACKOFF;
    loop {
        let parts = (&config, &*counters, &mut status);
        let ended = session(parts, &shutdown, sink, on_status).await;
        let frames_before = status.frames;
        status.connected = false;
        on_status(&status);
        match ended {
            Ok(Ended::Shutdown) => return Ok(()),
            Ok(Ended::Lost(why)) => {
                tracing::warn!(target: "emoshift", server = %config.server, why, "qtm: connection lost; reconnecting");
            }
            Err(e) => {
                tracing::warn!(target: "emoshift", server = %config.server, error = %format!("{e:#}"),
                    "qtm: no session; is QTM running there with real-time output on? retrying");
            }
        }
        if frames_before > 0 {
            backoff = FIRST_BACKOFF;
        }
        tokio::select! {
            () = shutdown.cancelled() => return Ok(()),
            () = tokio::time::sleep(backoff) => {}
        }
        backoff = (backoff * 2).min(MAX_BACKOFF);
        status.reconnects += 1;
    }
}

/// Where a session is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Step {
    Version,
    Parameters,
    Streaming,
}

/// One connection, from connect to its end.
async fn session(
    (config, counters, status): (&QtmConfig, &InputCounters, &mut QtmStatus),
    shutdown: &CancellationToken,
    sink: &mut FrameSink<'_>,
    on_status: &mut (dyn FnMut(&QtmStatus) + Send),
) -> Result<Ended> {
    let stream = tokio::time::timeout(CONNECT_TIMEOUT, TcpStream::connect(config.server))
        .await
        .context("connect timed out")?
        .with_context(|| format!("connecting to QTM at {}", config.server))?;
    stream.set_nodelay(true)?;
    tracing::info!(target: "emoshift", server = %config.server, "qtm: connected");
    let (mut reader, mut writer) = stream.into_split();
    let mut out = Vec::with_capacity(256);
    command(&mut writer, MAX_VERSION_TEXT, &mut out).await?;
    let mut framer = Framer::new(MAX_PACKET);
    let mut conn = Conn::new(config, counters, status);
    let mut tick = tokio::time::interval(STATUS_EVERY);
    loop {
        let n = tokio::select! {
            () = shutdown.cancelled() => return Ok(Ended::Shutdown),
            _ = tick.tick() => {
                on_status(conn.status);
                continue;
            }
            r = reader.read(framer.buffer()) => r.context("reading from QTM")?,
        };
        if n == 0 {
            return Ok(Ended::Lost("QTM closed the connection"));
        }
        framer.filled(n);
        loop {
            let packet = match framer.next_packet() {
                Ok(Some(p)) => p,
                Ok(None) => break,
                Err(e) => {
                    conn.bad_packet();
                    bail!("QTM sent garbage: {e}");
                }
            };
            match conn.handle(packet, sink)? {
                Next::Nothing => {}
                Next::Send(text) => {
                    command(&mut writer, text, &mut out).await?;
                    on_status(conn.status);
                }
                Next::End(why) => return Ok(Ended::Lost(why)),
            }
        }
    }
}

/// What a packet asks of the connection.
enum Next {
    Nothing,
    Send(&'static str),
    End(&'static str),
}

/// A session's state between packets.
struct Conn<'a> {
    config: &'a QtmConfig,
    counters: &'a InputCounters,
    status: &'a mut QtmStatus,
    frames: QtmFrames,
    buf: FrameBuf,
    step: Step,
    /// Parameters asked for and not yet read.
    asked: bool,
}

impl<'a> Conn<'a> {
    fn new(config: &'a QtmConfig, counters: &'a InputCounters, status: &'a mut QtmStatus) -> Self {
        let max_markers = protocol::MAX_FRAME_MARKERS;
        Conn {
            config,
            counters,
            status,
            frames: QtmFrames::new(config.server, max_markers),
            buf: FrameBuf::with_max_markers(max_markers),
            step: Step::Version,
            asked: false,
        }
    }

    fn bad_packet(&mut self) {
        InputCounters::add(&self.counters.bad_frames);
        self.status.bad_packets += 1;
    }

    /// Asks for the parameters unless they are on their way.
    fn reread(&mut self) -> Next {
        if self.asked || self.step != Step::Streaming {
            return Next::Nothing;
        }
        self.asked = true;
        Next::Send(GET_PARAMETERS)
    }

    /// One packet from QTM.
    fn handle(&mut self, packet: Packet<'_>, sink: &mut FrameSink<'_>) -> Result<Next> {
        Ok(match packet.kind {
            PacketType::Data if self.step == Step::Streaming => self.data(packet.payload, sink),
            PacketType::Command if self.step == Step::Version => {
                let text = packet.text().unwrap_or("");
                if !text.starts_with("Version set to") {
                    return Ok(Next::Nothing);
                }
                tracing::info!(target: "emoshift", answer = text, "qtm: version agreed");
                self.step = Step::Parameters;
                self.status.connected = true;
                Next::Send(GET_PARAMETERS)
            }
            PacketType::Error => {
                let text = packet.text().unwrap_or("?");
                self.status.qtm_errors += 1;
                if self.step == Step::Version {
                    bail!("QTM refused RT protocol 1.25 ({text}): QTM 2019 or later speaks it");
                }
                tracing::warn!(target: "emoshift", error = text, "qtm: QTM answered with an error");
                Next::Nothing
            }
            PacketType::Xml => self.parameters(packet.text().unwrap_or("")),
            PacketType::Event => {
                let Ok(event) = packet.event() else {
                    self.bad_packet();
                    return Ok(Next::Nothing);
                };
                self.status.last_event = format!("{event:?}");
                tracing::info!(target: "emoshift", event = ?event, "qtm: event");
                if event == Event::QtmShuttingDown {
                    return Ok(Next::End("QTM is shutting down"));
                }
                if event.rereads_parameters() {
                    return Ok(self.reread());
                }
                Next::Nothing
            }
            _ => Next::Nothing,
        })
    }

    /// A data packet: its streams to the sink.
    fn data(&mut self, payload: &[u8], sink: &mut FrameSink<'_>) -> Next {
        let arrival = Arrival {
            received: Instant::now(),
            captured: None,
            answer: None,
            announced_rate_hz: self.frames.rate_hz,
        };
        let mut out = |f: &engine::SourceFrame<'_>| sink(f, &arrival);
        match self.frames.handle_data(payload, &mut self.buf, &mut out) {
            Ok(Outcome::Frames(_)) => {
                InputCounters::add(&self.counters.frames_in);
                self.status.frames += 1;
                Next::Nothing
            }
            Ok(Outcome::No3d) => Next::Nothing,
            Ok(Outcome::Mismatch) => {
                InputCounters::add(&self.counters.dropped_no_layout);
                self.reread()
            }
            Err(_) => {
                self.bad_packet();
                Next::Nothing
            }
        }
    }

    /// The parameters: the streams again; the first time, streaming starts.
    fn parameters(&mut self, xml: &str) -> Next {
        let p = match decode_parameters(xml) {
            Ok(p) => p,
            Err(e) => {
                self.bad_packet();
                tracing::warn!(target: "emoshift", error = %e, "qtm: unreadable parameters");
                return Next::Nothing;
            }
        };
        self.frames.set_parameters(&p, &self.config.performers);
        self.status.labels = self.frames.label_count();
        self.status.streams = self.frames.stream_names().join(",");
        tracing::info!(target: "emoshift", labels = self.status.labels,
            rate_hz = ?self.frames.rate_hz, streams = %self.status.streams, "qtm: parameters read");
        self.asked = false;
        if self.step != Step::Parameters {
            return Next::Nothing;
        }
        self.step = Step::Streaming;
        tracing::info!(target: "emoshift", "qtm: streaming 3D and Timecode over TCP");
        Next::Send(STREAM)
    }
}

/// Sends one command.
async fn command(writer: &mut OwnedWriteHalf, text: &str, out: &mut Vec<u8>) -> Result<()> {
    encode_text_into(PacketType::Command, text, out);
    writer.write_all(out).await.context("writing to QTM")?;
    Ok(())
}
