//! `emoshift serve`: the live service, the shell around one [`engine::Pipeline`]. It owns
//! what the engine may not: the tokio runtime, sockets, threads, the clock and files.
//!
//! - [`sources`]: one folder per input protocol (OSC, NatNet), each turning its protocol into
//!   the engine's [`engine::SourceFrame`]s;
//! - [`sinks`]: one folder per output (the OSC profiles, the session recording), each an
//!   [`engine::Sink`];
//! - [`config`]: TOML + CLI → one validated [`Config`] ([`config_error`] names a bad key);
//! - `server`: binds the sockets and runs the tasks (sources, control, the status log,
//!   signals); the only code that awaits, with `control`;
//! - `control`: control datagrams → [`command`](self) requests to the processing thread, and
//!   the replies;
//! - [`queue`]: the sources' frames to the processing thread, pooled, latest frame wins;
//! - `processing`: the processing thread: OSC frames off the frame socket it reads itself and
//!   the other sources' frames off the queue, through the engine to the sinks, commands
//!   between frames, counters merged into [`stats`]; [`wake`]: its doorbell;
//! - [`arrival`]: when the processing thread polls instead of parking (a steady source's
//!   beat);
//! - [`monitor`]: the monitor page (HTTP + WebSocket, and its feed, a sink), when `monitor`
//!   is set;
//! - [`net`], [`allow`], [`latency`]: sockets, allow-lists, latency histograms;
//! - [`capture`]: `emoshift record`, one live source (OSC or NatNet) captured to one file.
//!
//! Entry points: [`run`] (bind, then serve until the token is cancelled), or [`bind`] then
//! [`Bound::run`] to learn the bound addresses first (tests bind `127.0.0.1:0`).

pub mod allow;
pub mod arrival;
pub mod capture;
mod command;
pub mod config;
pub mod config_error;
mod control;
mod guard;
pub mod latency;
pub mod monitor;
pub mod net;
pub(crate) mod processing;
pub mod queue;
pub(crate) mod server;
pub mod session;
pub mod sinks;
pub mod sources;
pub mod stats;
pub mod wake;

pub use config::Config;
pub use server::{bind, bind_with, Bound};

use anyhow::Context as _;
use ica_core::model::IcaModel;
use tokio_util::sync::CancellationToken;

/// Binds, loads the models and serves until `shutdown` is cancelled; then stops receiving,
/// finishes the frames in flight, closes the recording and returns.
///
/// # Errors
/// A socket that cannot be bound, a model that cannot be loaded, a task that failed.
pub async fn run(config: Config, shutdown: CancellationToken) -> anyhow::Result<()> {
    bind(config).await?.run(shutdown).await
}

/// Loads a model file of at most `max_bytes` on a blocking thread.
///
/// # Errors
/// Unreadable, not a regular file, too large or invalid, named.
pub async fn load_model(path: std::path::PathBuf, max_bytes: u64) -> anyhow::Result<IcaModel> {
    tokio::task::spawn_blocking(move || crate::offline::load_model_limited(&path, max_bytes))
        .await
        .context("model loader panicked")?
}
