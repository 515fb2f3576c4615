//! `emoshift demo --monitor`: after training and analysis, the daemon keeps running with the
//! monitor page served and the take replayed in a loop, until Ctrl-C. A client subscribed with
//! the compact profile renews its lease meanwhile, so the page's health lists a subscriber.

use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use anyhow::{Context, Result};
use ica_core::model::IcaModel;
use protocol::Profile;
use replay::pacer::{Pacer, PacerOptions};
use replay::Take;

use crate::loopback::source::{drive, take_labels, SPIN};
use crate::loopback::{ControlClient, Daemon, Receiver};
use crate::serve::config::RawConfig;

/// Serves `model` with the monitor page at `monitor` while `take` loops, until Ctrl-C.
pub(super) fn serve(model: &IcaModel, take: Arc<Take>, monitor: &str) -> Result<()> {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("cannot start the runtime")?;
    runtime.block_on(async {
        let config = RawConfig {
            listen: Some("127.0.0.1:0".into()),
            control: Some("127.0.0.1:0".into()),
            model: Some("model.json".into()),
            monitor: Some(monitor.to_string()),
            ..Default::default()
        }
        .validate()
        .map_err(|e| crate::exit::UsageError(format!("--monitor: {e}")))?;
        let daemon = Daemon::start_with(config, model.clone()).await?;
        let result = looping(&daemon, take).await;
        daemon.stop(Duration::from_secs(2)).await?;
        result
    })
}

async fn looping(daemon: &Daemon, take: Arc<Take>) -> Result<()> {
    let control = ControlClient::new(daemon.control).await?;
    let client = Receiver::subscribe(&control, Profile::Compact).await?;
    let received = client.collect(None, 0u64, |n, r| *n += u64::from(r.frame.is_some()));
    crate::out!(
        "daemon: frames on {}, control on {}; a client subscribed at {}",
        daemon.frames,
        daemon.control,
        client.addr()?
    );
    crate::out!(
        "replaying {} frames at {} Hz in a loop; open the monitor page above; Ctrl-C stops",
        take.n_frames(),
        take.rate_hz
    );
    let stop = Arc::new(AtomicBool::new(false));
    let (to, stop2) = (daemon.frames, Arc::clone(&stop));
    let sender = tokio::task::spawn_blocking(move || send_forever(&take, to, &stop2));
    let ended = tokio::select! {
        r = tokio::signal::ctrl_c() => r.context("cannot wait for Ctrl-C"),
        r = sender => match r {
            Ok(Ok(())) => Ok(()),
            Ok(Err(e)) => Err(e),
            Err(e) => Err(anyhow::anyhow!("the sender panicked: {e}")),
        },
    };
    stop.store(true, Ordering::Relaxed);
    let frames = received.stop().await?;
    crate::out!("\nstopped; the client received {frames} frames");
    ended
}

/// Replays `take` in a loop at its rate until `stop`.
fn send_forever(take: &Take, to: SocketAddr, stop: &AtomicBool) -> Result<()> {
    let socket = UdpSocket::bind("127.0.0.1:0")?;
    let mut source = crate::loopback::Source::new(&take_labels(take, 0), socket, to, false)?;
    let options = PacerOptions {
        first_frame_number: take.first_frame,
        looping: true,
        ..PacerOptions::default()
    };
    let mut pacer = Pacer::new(take.rate_hz, take.n_frames(), options)?;
    drive(&mut pacer, SPIN, stop, |due| {
        source.send_due(take, due).map(|()| true)
    })
}
