//! The daemon in this process, as `emoshift serve` runs it: its own thread and tokio runtime
//! (two workers), so the caller's runtime, blocking sends or timing loops do not share its
//! threads.

use std::net::SocketAddr;
use std::time::Duration;

use anyhow::{Context, Result};
use ica_core::model::IcaModel;
use tokio_util::sync::CancellationToken;

use crate::serve::config::{ConfigError, RawConfig};
use crate::serve::{self, Config};

/// A running daemon and its bound addresses.
#[derive(Debug)]
pub struct Daemon {
    /// Where it receives frames.
    pub frames: SocketAddr,
    /// Where it receives control.
    pub control: SocketAddr,
    /// Where it serves the monitor page, when `monitor` is set.
    pub monitor: Option<SocketAddr>,
    /// The NatNet server's command address, when `natnet_server` is set.
    pub natnet_server: Option<SocketAddr>,
    /// The QTM server's RT address, when `qtm_server` is set.
    pub qtm_server: Option<SocketAddr>,
    shutdown: CancellationToken,
    done: Option<tokio::sync::oneshot::Receiver<Result<()>>>,
}

impl Daemon {
    /// Binds `config` (loading its model file) and starts serving.
    ///
    /// # Errors
    /// What `emoshift serve` would report: an unreadable model, a port that cannot be bound.
    pub async fn start(config: Config) -> Result<Daemon> {
        Daemon::launch(config, None).await
    }

    /// Binds `config` with `model` in place of its model file and starts serving.
    ///
    /// # Errors
    /// As [`Daemon::start`].
    pub async fn start_with(config: Config, model: IcaModel) -> Result<Daemon> {
        Daemon::launch(config, Some(model)).await
    }

    async fn launch(config: Config, model: Option<IcaModel>) -> Result<Daemon> {
        let (bound_tx, bound_rx) = tokio::sync::oneshot::channel();
        let (done_tx, done) = tokio::sync::oneshot::channel();
        let shutdown = CancellationToken::new();
        let token = shutdown.clone();
        std::thread::Builder::new()
            .name("loopback-daemon".into())
            .spawn(move || {
                let result = serve_until(config, model, token, bound_tx);
                let _ = done_tx.send(result);
            })
            .context("cannot start the daemon thread")?;
        let (frames, control, monitor, natnet_server, qtm_server) =
            bound_rx.await.context("the daemon thread ended")??;
        Ok(Daemon {
            frames,
            control,
            monitor,
            natnet_server,
            qtm_server,
            shutdown,
            done: Some(done),
        })
    }

    /// Asks it to shut down and waits up to `within` for it to finish.
    ///
    /// # Errors
    /// It did not stop in time, or it stopped with an error.
    pub async fn stop(mut self, within: Duration) -> Result<()> {
        self.shutdown.cancel();
        let done = self.done.take().context("the daemon was already stopped")?;
        tokio::time::timeout(within, done)
            .await
            .with_context(|| format!("the daemon did not stop within {within:?}"))?
            .context("the daemon thread panicked")?
    }
}

impl Drop for Daemon {
    /// A daemon dropped unstopped (a failed test, an early return) still shuts down.
    fn drop(&mut self) {
        self.shutdown.cancel();
    }
}

/// The config of a daemon on ephemeral loopback ports (`--listen 127.0.0.1:0 --control
/// 127.0.0.1:0`) for [`Daemon::start_with`], with the monitor page at `monitor` when given.
///
/// # Errors
/// A `monitor` address that is not `IP:PORT`.
pub fn loopback_config(monitor: Option<&str>) -> Result<Config, ConfigError> {
    RawConfig {
        listen: Some("127.0.0.1:0".into()),
        control: Some("127.0.0.1:0".into()),
        model: Some("model.json".into()),
        monitor: monitor.map(str::to_string),
        ..Default::default()
    }
    .validate()
}

type Bound = Result<(
    SocketAddr,
    SocketAddr,
    Option<SocketAddr>,
    Option<SocketAddr>,
    Option<SocketAddr>,
)>;

fn serve_until(
    config: Config,
    model: Option<IcaModel>,
    shutdown: CancellationToken,
    bound_tx: tokio::sync::oneshot::Sender<Bound>,
) -> Result<()> {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("cannot start the daemon's runtime")?;
    runtime.block_on(async move {
        let bound = match model {
            Some(model) => serve::bind_with(config, model).await,
            None => serve::bind(config).await,
        };
        let addrs = bound
            .as_ref()
            .map_err(|e| anyhow::anyhow!("{e:#}"))
            .and_then(|b| {
                let (frames, control) = (b.frame_addr()?, b.control_addr()?);
                let servers = (b.natnet_server_addr()?, b.qtm_server_addr()?);
                Ok((frames, control, b.monitor_addr()?, servers.0, servers.1))
            });
        let _ = bound_tx.send(addrs);
        bound?.run(shutdown).await
    })
}
