//! A paced source on the wall clock: [`replay::pacer::Pacer`] decides when, [`drive`] waits and
//! calls back, a [`Source`] puts labels and frames on a socket. `emoshift replay`, the demo, the
//! bench and the end-to-end tests all send this way, so they send exactly like a live source.
//!
//! [`drive`] sleeps until `spin` before each deadline and spins the rest when `spin` is not
//! zero: a sleep alone overshoots by the scheduler's slack (often 50-100 µs, more under load),
//! and spinning a whole period would burn a core for nothing. The bench passes zero: on a small
//! machine a spinning sender takes a core from the daemon it measures.

use std::collections::HashMap;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use protocol::{encode_frame_flat_into, encode_frame_into, encode_labels_into, FrameBuf, Labels};
use replay::pacer::{Action, FrameSend, Pacer, PacerOptions};
use replay::Take;

/// How long before a deadline a take's sender stops sleeping and spins.
pub const SPIN: Duration = Duration::from_micros(200);
/// Longest single sleep, so a stop request is noticed promptly between sparse deadlines.
const MAX_NAP: Duration = Duration::from_millis(50);

/// What is due from a paced source.
#[derive(Debug, Clone, Copy)]
pub enum Due<'a> {
    /// The labels (at the start, then every second).
    Labels,
    /// A frame.
    Frame(&'a FrameSend),
}

/// Runs `pacer` on the wall clock until it is done, `stop` is raised, or `send` returns
/// `false`; calls `send` with what is due when it is due.
///
/// # Errors
/// The first error `send` returns.
pub fn drive(
    pacer: &mut Pacer,
    spin: Duration,
    stop: &AtomicBool,
    mut send: impl FnMut(Due<'_>) -> Result<bool>,
) -> Result<()> {
    let origin = Instant::now();
    while !stop.load(Ordering::Relaxed) {
        let go_on = match pacer.poll(origin.elapsed()) {
            Action::SendLabels => send(Due::Labels)?,
            Action::SendFrame(f) => send(Due::Frame(&f))?,
            Action::Sleep { until } => {
                wait_until(origin + until, spin, stop);
                true
            }
            Action::Done => false,
        };
        if !go_on {
            break;
        }
    }
    Ok(())
}

/// Replays `take` from a loopback socket to `to` at its rate, looping, until `stop` is raised
/// or, with `limit`, that many frames are out; `sending` hears each frame's number just before
/// it goes. Returns how many frames the pacer sent late.
///
/// # Errors
/// No socket, a take the pacer refuses, a failed send.
pub fn play_take(
    take: &Take,
    to: SocketAddr,
    limit: Option<usize>,
    stop: &AtomicBool,
    mut sending: impl FnMut(i64),
) -> Result<u64> {
    let socket = UdpSocket::bind("127.0.0.1:0").context("cannot open a udp socket")?;
    let mut source = Source::new(&take_labels(take, 0), socket, to, false)?;
    let options = PacerOptions {
        first_frame_number: take.first_frame,
        looping: true,
        ..PacerOptions::default()
    };
    let mut pacer = Pacer::new(take.rate_hz, take.n_frames(), options)?;
    drive(&mut pacer, SPIN, stop, |due| {
        if let Due::Frame(f) = due {
            if limit.is_some_and(|n| f.stream_index as usize >= n) {
                return Ok(false);
            }
            sending(f.frame_number);
        }
        source.send_due(take, due).map(|()| true)
    })?;
    Ok(pacer.summary().late_frames)
}

/// Replays `total` frames of `take` to `to` at its rate (looping): when each frame number
/// went, and how many the pacer sent late.
///
/// # Errors
/// As [`play_take`].
pub fn play_take_timed(
    take: &Take,
    to: SocketAddr,
    total: usize,
) -> Result<(HashMap<i64, Instant>, u64)> {
    let mut sent = HashMap::with_capacity(total);
    let late = play_take(take, to, Some(total), &AtomicBool::new(false), |n| {
        sent.insert(n, Instant::now());
    })?;
    Ok((sent, late))
}

/// Sleeps until `spin` before `deadline`, then spins; returns early on a stop request.
pub fn wait_until(deadline: Instant, spin: Duration, stop: &AtomicBool) {
    loop {
        let now = Instant::now();
        if now >= deadline || stop.load(Ordering::Relaxed) {
            return;
        }
        let left = deadline - now;
        if left > spin {
            std::thread::sleep((left - spin).min(MAX_NAP));
        } else {
            std::hint::spin_loop();
        }
    }
}

/// Labels and frames onto one socket, with the buffers every send reuses.
#[derive(Debug)]
pub struct Source {
    socket: UdpSocket,
    to: SocketAddr,
    flat: bool,
    labels: Vec<u8>,
    frame: FrameBuf,
    datagram: Vec<u8>,
    /// Sends that failed (counted; the source goes on, as a live one would).
    pub send_errors: u64,
}

impl Source {
    /// A source of frames labelled `labels`, sending from `socket` to `to`, in the blob form or
    /// (`flat`) the flat form.
    ///
    /// # Errors
    /// A label the wire format cannot carry.
    pub fn new(labels: &Labels, socket: UdpSocket, to: SocketAddr, flat: bool) -> Result<Source> {
        let mut encoded = Vec::new();
        encode_labels_into(labels, &mut encoded).context("the labels cannot be sent")?;
        let n = labels.names.len();
        Ok(Source {
            socket,
            to,
            flat,
            labels: encoded,
            frame: FrameBuf::with_max_markers(n),
            datagram: Vec::with_capacity(protocol::frame_message_len(n) + 4 * n),
            send_errors: 0,
        })
    }

    /// A source on a new loopback socket, labels sent right away.
    ///
    /// # Errors
    /// No socket, or a label the wire format cannot carry.
    pub fn on_loopback(labels: &Labels, to: SocketAddr) -> Result<Source> {
        let socket = UdpSocket::bind("127.0.0.1:0").context("cannot open a udp socket")?;
        let mut source = Source::new(labels, socket, to, false)?;
        source.send_labels();
        Ok(source)
    }

    /// Where it sends.
    pub fn to(&self) -> SocketAddr {
        self.to
    }

    /// Its socket (to read what the daemon answers a source).
    pub fn socket(&self) -> &UdpSocket {
        &self.socket
    }

    /// Sends the labels.
    pub fn send_labels(&mut self) {
        let result = self.socket.send_to(&self.labels, self.to);
        self.count(result);
    }

    /// Sends one frame; `missing` flags markers that are absent (empty: none).
    ///
    /// # Errors
    /// A frame the wire format cannot carry (a present coordinate that is not finite, too many
    /// markers).
    pub fn send_frame(
        &mut self,
        number: i32,
        capture_time_us: i64,
        xyz: &[f32],
        missing: &[bool],
    ) -> Result<()> {
        self.frame.set_frame(number, capture_time_us, xyz)?;
        for (m, &gone) in missing.iter().enumerate() {
            if gone {
                self.frame.set_missing(m, true);
            }
        }
        if self.flat {
            encode_frame_flat_into(&self.frame, &mut self.datagram)?;
        } else {
            encode_frame_into(&self.frame, &mut self.datagram)?;
        }
        let result = self.socket.send_to(&self.datagram, self.to);
        self.count(result);
        Ok(())
    }

    /// Sends what is due of `take`: its labels or its frame `f`.
    ///
    /// # Errors
    /// As [`Source::send_take_frame`].
    pub fn send_due(&mut self, take: &Take, due: Due<'_>) -> Result<()> {
        match due {
            Due::Labels => {
                self.send_labels();
                Ok(())
            }
            Due::Frame(f) => self.send_take_frame(take, f),
        }
    }

    /// Sends frame `f` of `take` (the pacer's frame number and capture time).
    ///
    /// # Errors
    /// As [`Source::send_frame`], naming the frame.
    pub fn send_take_frame(&mut self, take: &Take, f: &FrameSend) -> Result<()> {
        // The OSC int32 frame number wraps after 2^31 frames (207 days at 120 Hz).
        let number = f.frame_number as i32;
        let (xyz, missing) = (take.frame(f.index), take.frame_missing(f.index));
        self.send_frame(number, f.capture_time_us, xyz, missing)
            .with_context(|| format!("frame index {} cannot be sent", f.index))
    }

    /// Sends bytes as they are (a prepared or deliberately malformed datagram).
    pub fn send_raw(&mut self, bytes: &[u8]) {
        let result = self.socket.send_to(bytes, self.to);
        self.count(result);
    }

    fn count(&mut self, result: std::io::Result<usize>) {
        if let Err(e) = result {
            if self.send_errors == 0 {
                tracing::warn!(target: "emoshift", to = %self.to, error = %e, "send failed; counting further failures");
            }
            self.send_errors += 1;
        }
    }
}

/// The labels of a take, under layout id `layout_id`.
pub fn take_labels(take: &Take, layout_id: i32) -> Labels {
    Labels {
        layout_id,
        names: take.labels.clone(),
    }
}
