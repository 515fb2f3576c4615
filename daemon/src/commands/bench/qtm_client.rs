//! The bench's QTM RT client: one TCP connection to the daemon's `--qtm-server`, protocol 1.25,
//! `StreamFrames AllFrames 3D`, each frame timed from its timestamp (the source's capture time,
//! µs on the bench's clock) as the OSC receivers time theirs.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use anyhow::{Context, Result};
use protocol::qtm::{decode_data_into, encode_text_into, FrameIn, Framer, PacketType};

use super::harness::{epoch, Seen};
use super::MARKERS;
use crate::serve::stats::Stats;

/// Packets larger than this end the client (the daemon's frames are far smaller).
const MAX_PACKET: usize = 1 << 20;

/// A QTM RT client streaming 3D over TCP.
pub(super) struct QtmClient {
    stream: TcpStream,
}

impl QtmClient {
    /// Connects and asks for every frame's 3D; frames flow once the daemon has a stream.
    pub(super) fn connect(server: SocketAddr) -> Result<QtmClient> {
        let mut stream = TcpStream::connect(server).context("cannot reach the QTM server")?;
        stream.set_nodelay(true)?;
        stream.set_read_timeout(Some(Duration::from_millis(20)))?;
        let mut out = Vec::new();
        for command in ["Version 1.25", "StreamFrames AllFrames 3D"] {
            encode_text_into(PacketType::Command, command, &mut out);
            stream.write_all(&out)?;
        }
        Ok(QtmClient { stream })
    }

    /// Reads until `stop`: frames received and their latency since capture.
    pub(super) fn run(mut self, stop: &AtomicBool) -> Seen {
        let mut seen = Seen::new();
        let mut framer = Framer::new(MAX_PACKET);
        let mut frame = FrameIn::with_max_markers(MARKERS * 64);
        while !stop.load(Ordering::Relaxed) {
            let n = match self.stream.read(framer.buffer()) {
                Ok(0) => break,
                Ok(n) => n,
                Err(_) => continue,
            };
            framer.filled(n);
            let now = epoch().elapsed().as_micros() as u64;
            while let Ok(Some(p)) = framer.next_packet() {
                // Warm-up frames are numbered below 0: QTM's u32 carries the i32 wrapped.
                if p.kind != PacketType::Data
                    || decode_data_into(p.payload, &mut frame).is_err()
                    || i32::try_from(frame.frame_number).is_err()
                {
                    continue;
                }
                seen.received += 1;
                let sent_us = u64::try_from(frame.timestamp_us).unwrap_or(0);
                Stats::record(&mut seen.latency_us, now.saturating_sub(sent_us));
            }
        }
        seen
    }
}
