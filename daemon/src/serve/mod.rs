//! `emoshift serve`: the live service, the shell around one [`crate::engine::Pipeline`]. It
//! owns what the engine may not: the tokio runtime, sockets, threads, the clock and files.
//!
//! - [`config`]: TOML + CLI → one validated [`Config`];
//! - `server`: binds the sockets and runs the tasks (the receive task, the control task, the
//!   status log, signals); the only code that awaits, with `control`;
//! - `control`: control datagrams → [`command`](self) requests to the processing thread, and
//!   the replies;
//! - `processing`: the processing thread: frames through the engine, commands between
//!   frames, the recording, counters merged into [`stats`];
//! - `sender`: the processing thread's fan-out to the subscribers;
//! - [`arrival`]: when the processing thread polls instead of parking (a steady source's
//!   beat);
//! - [`record`]: recordings of the edited stream and the raw input;
//! - [`monitor`]: the monitor page (HTTP + WebSocket), when `monitor` is set;
//! - [`net`]: sockets (large receive buffers, connected senders);
//! - [`natnet`]: OptiTrack Motive's NatNet stream as a source beside the OSC frame socket;
//! - [`capture`]: `emoshift record`, a live source (OSC or NatNet) captured to one file.
//!
//! Entry points: [`run`] (bind, then serve until the token is cancelled), or [`bind`] then
//! [`Bound::run`] to learn the bound addresses first (tests bind `127.0.0.1:0`).

pub mod allow;
pub mod arrival;
pub mod capture;
mod command;
pub mod config;
mod control;
mod guard;
mod latency;
pub mod monitor;
pub mod natnet;
pub mod net;
pub(crate) mod processing;
pub mod record;
mod record_sink;
mod sender;
pub(crate) mod server;
pub mod stats;

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
