//! The bench's NatNet source mode (`emoshift bench --natnet`): the same performers and
//! receivers as the OSC rounds, but the frames come from a Motive stand-in on loopback
//! (multicast with TTL 0, Motive's default, or unicast), one NAT_FRAMEOFDATA per tick carrying every performer as a markerset,
//! each frame's mid-exposure stamp the send time on the bench's clock (the stand-in's clock
//! runs at 1 MHz from the bench's epoch), so the receivers time the same path end to end.

use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use ica_core::model::IcaModel;
use protocol::natnet::{FrameOfData, MarkersetDef, ModelDefs, NatNetVersion};
use replay::pacer::{Pacer, PacerOptions};

use super::harness::{collect, daemon_config, epoch, receivers, Run};
use super::MARKERS;
use crate::loopback::motive::{Motive, MotiveOptions};
use crate::loopback::source::{drive, Due};
use crate::loopback::{ControlClient, Daemon};
use crate::serve::config::RawConfig;
use engine::synthetic::frame_into;

/// A free multicast port on loopback.
fn free_port() -> Result<u16> {
    Ok(UdpSocket::bind("127.0.0.1:0")?.local_addr()?.port())
}

/// Paced NatNet traffic through the daemon: `performers` markersets at 120 Hz for `secs`,
/// multicast (Motive's default) or unicast.
pub(super) async fn through_daemon_natnet(
    model: &IcaModel,
    (performers, clients): (usize, usize),
    secs: Duration,
    poll_window_us: u64,
    multicast: bool,
) -> Result<Run> {
    let (receivers, addrs) = receivers(clients).await?;
    let names: Vec<String> = (0..performers).map(|p| format!("P{p}")).collect();
    let defs = ModelDefs {
        markersets: names
            .iter()
            .map(|n| MarkersetDef {
                name: n.clone(),
                marker_names: model.labels().to_vec(),
            })
            .collect(),
        ..ModelDefs::default()
    };
    let group: SocketAddr = format!("239.255.42.99:{}", free_port()?).parse()?;
    let server = Motive::start(MotiveOptions {
        command: "127.0.0.1:0".parse()?,
        multicast: multicast.then_some(group),
        version: NatNetVersion::V4_1,
        defs,
        epoch: epoch(),
        rate_hz: 120.0,
    })?;
    let raw = RawConfig {
        natnet: Some(server.command_addr().to_string()),
        natnet_names: Some("marker".into()),
        ..daemon_config(&addrs, poll_window_us)
    };
    let daemon = Daemon::start_with(raw.validate()?, model.clone()).await?;
    let traffic = async {
        let control = ControlClient::new(daemon.control).await?;
        wait_for_session(&control, performers).await?;
        let sent = send_natnet(model, server, &names, secs).await?;
        tokio::time::sleep(Duration::from_millis(200)).await;
        let status = control.status().await?;
        anyhow::Ok((sent, status))
    }
    .await;
    daemon.stop(Duration::from_secs(5)).await?;
    let (sent, status) = traffic?;
    Ok(Run {
        seen: collect(receivers).await,
        sent,
        status,
    })
}

/// Waits until the daemon has the stand-in's model definitions.
async fn wait_for_session(control: &ControlClient, performers: usize) -> Result<()> {
    for _ in 0..200 {
        let status = control.status().await?;
        let sets = crate::loopback::text(&status, "natnet/markersets").unwrap_or("");
        if sets.matches("markers)").count() == performers {
            return Ok(());
        }
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
    anyhow::bail!("the daemon did not get the stand-in's model definitions in 5 s")
}

/// One frame per tick with every performer's markerset, on absolute deadlines (as the OSC
/// senders); returns frames sent, counted per performer as the OSC rounds count them.
async fn send_natnet(
    model: &IcaModel,
    mut server: Motive,
    names: &[String],
    secs: Duration,
) -> Result<u64> {
    let sets: Vec<Vec<[f32; 3]>> = (0..names.len())
        .map(|p| {
            let mut xyz = vec![0.0f32; MARKERS * 3];
            frame_into(model, p, &mut xyz);
            xyz.chunks_exact(3)
                .map(|c| [c[0] / 1e3, c[1] / 1e3, c[2] / 1e3])
                .collect()
        })
        .collect();
    let frames = (120.0 * secs.as_secs_f64()) as usize;
    let options = PacerOptions {
        max_behind_frames: u64::MAX,
        ..PacerOptions::default()
    };
    let mut pacer = Pacer::new(120.0, frames.max(1), options)?;
    let names = names.to_vec();
    let thread = tokio::task::spawn_blocking(move || {
        std::thread::sleep(Duration::from_millis(20));
        let mut f = FrameOfData::with_capacity(MARKERS * names.len(), 4);
        let mut sent = 0u64;
        drive(&mut pacer, Duration::ZERO, &AtomicBool::new(false), |due| {
            let Due::Frame(d) = due else {
                return Ok(true);
            };
            f.clear();
            f.frame_number = d.stream_index as i32;
            for (name, set) in names.iter().zip(&sets) {
                f.push_markerset(name, set);
            }
            f.camera_mid_exposure = server.ticks(Instant::now());
            f.transmit = f.camera_mid_exposure;
            if server.send(&f)? == 1 {
                sent += names.len() as u64;
            }
            Ok(true)
        })
        .map(|()| {
            server.stop();
            sent
        })
    });
    thread.await.context("NatNet sender thread")?
}
