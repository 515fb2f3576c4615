//! The bench's server-output modes (`emoshift bench --natnet-server`, `--qtm-server`): the same
//! paced OSC performers through the daemon, with one client on its NatNet server (unicast,
//! bitstream 4.1) or its QTM server (TCP, `StreamFrames AllFrames 3D`) beside the OSC compact
//! receivers, in the same run. Both outputs keep the source's capture time (the send time on
//! the bench's clock) as the frame's timestamp, so the client times the same path end to end
//! as the OSC receivers do.

use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use ica_core::model::IcaModel;
use protocol::natnet::{
    check_packet, decode_frame_into, encode_connect_into, encode_empty_into, Connect, FrameOfData,
    MessageId, NatNetVersion,
};

use super::harness::{collect, daemon_config, epoch, receivers, send_all, Run, Seen};
use super::qtm_client::QtmClient;
use super::MARKERS;
use crate::loopback::{ControlClient, Daemon};
use crate::serve::stats::Stats;

/// The server output a round's client reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum ServerOutput {
    /// `--natnet-server`, unicast 4.1.
    NatNet,
    /// `--qtm-server`, TCP.
    Qtm,
}

/// The client's thread, started on `daemon`'s server `output`.
fn start_client(
    daemon: &Daemon,
    output: ServerOutput,
    stop: &Arc<AtomicBool>,
) -> Result<std::thread::JoinHandle<Seen>> {
    let stop = Arc::clone(stop);
    Ok(match output {
        ServerOutput::NatNet => {
            let server = daemon.natnet_server.context("the daemon serves NatNet")?;
            let client = NatNetClient::connect(server)?;
            std::thread::spawn(move || client.run(&stop))
        }
        ServerOutput::Qtm => {
            let server = daemon.qtm_server.context("the daemon serves QTM")?;
            let client = QtmClient::connect(server)?;
            std::thread::spawn(move || client.run(&stop))
        }
    })
}

/// Keep-alives this often (NatNetLib sends one a second).
const KEEP_ALIVE_EVERY: Duration = Duration::from_millis(500);

/// One paced round: the OSC receivers' run, and what the client of `output` saw.
pub(super) async fn through_daemon_server(
    model: &IcaModel,
    (performers, clients): (usize, usize),
    secs: Duration,
    poll_window_us: u64,
    output: ServerOutput,
) -> Result<(Run, Seen)> {
    let (receivers, addrs) = receivers(clients).await?;
    let mut raw = daemon_config(&addrs, poll_window_us);
    match output {
        ServerOutput::NatNet => raw.natnet_server = Some("127.0.0.1:0".into()),
        ServerOutput::Qtm => {
            raw.qtm_server = Some("127.0.0.1:0".into());
            raw.qtm_server_discovery = Some("off".into());
        }
    }
    let daemon = Daemon::start_with(raw.validate()?, model.clone()).await?;
    let stop = Arc::new(AtomicBool::new(false));
    let thread = start_client(&daemon, output, &stop)?;
    let traffic = async {
        // The client's first keep-alive (NatNet) or stream request (QTM) makes it a receiver;
        // a moment for it to land.
        tokio::time::sleep(Duration::from_millis(50)).await;
        let sent = send_all(model, performers, daemon.frames, 120.0, secs).await?;
        tokio::time::sleep(Duration::from_millis(200)).await;
        let status = ControlClient::new(daemon.control).await?.status().await?;
        anyhow::Ok((sent, status))
    }
    .await;
    stop.store(true, Ordering::Relaxed);
    daemon.stop(Duration::from_secs(5)).await?;
    let client = tokio::task::spawn_blocking(move || thread.join())
        .await
        .context("joining the server output's client")?
        .map_err(|_| anyhow::anyhow!("the server output's client panicked"))?;
    let (sent, status) = traffic?;
    let run = Run {
        seen: collect(receivers).await,
        sent,
        status,
    };
    Ok((run, client))
}

/// A minimal unicast NatNet client: connect, keep-alives, frames timed from their timestamp.
struct NatNetClient {
    socket: UdpSocket,
    server: SocketAddr,
}

impl NatNetClient {
    fn connect(server: SocketAddr) -> Result<NatNetClient> {
        let socket = UdpSocket::bind("127.0.0.1:0")?;
        socket.set_read_timeout(Some(Duration::from_millis(20)))?;
        let mut out = Vec::new();
        encode_connect_into(&Connect::emoshift(NatNetVersion::V4_1), false, &mut out)?;
        socket.send_to(&out, server)?;
        encode_empty_into(MessageId::KeepAlive, &mut out);
        socket.send_to(&out, server)?;
        Ok(NatNetClient { socket, server })
    }

    fn run(self, stop: &AtomicBool) -> Seen {
        let mut seen = Seen::new();
        let mut frame = FrameOfData::with_capacity(MARKERS, 0);
        let mut buf = vec![0u8; 65_536];
        let mut keep_alive = Vec::new();
        encode_empty_into(MessageId::KeepAlive, &mut keep_alive);
        let mut next = Instant::now() + KEEP_ALIVE_EVERY;
        while !stop.load(Ordering::Relaxed) {
            if Instant::now() >= next {
                let _ = self.socket.send_to(&keep_alive, self.server);
                next += KEEP_ALIVE_EVERY;
            }
            let Ok(n) = self.socket.recv(&mut buf) else {
                continue;
            };
            let now = epoch().elapsed().as_micros() as u64;
            let datagram = &buf[..n];
            if check_packet(datagram) != Ok(MessageId::FrameOfData)
                || decode_frame_into(datagram, NatNetVersion::V4_1, &mut frame).is_err()
                || frame.frame_number < 0
            {
                continue;
            }
            seen.received += 1;
            let sent_us = (frame.timestamp * 1e6).round() as u64;
            Stats::record(&mut seen.latency_us, now.saturating_sub(sent_us));
        }
        seen
    }
}
