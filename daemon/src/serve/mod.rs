//! `emoshift serve`: the live service.
//!
//! - [`config`]: TOML + CLI → one validated [`Config`];
//! - [`pipeline`]: the sans-IO frame path (decode → map labels → project → edit → resynthesise
//!   → encode), owning every buffer;
//! - [`edit_state`]: the live emotion edit (target, amount, ramp, low-pass, alpha, gains,
//!   bypass) on a frame clock;
//! - [`streams`]: one stream per source address and layout id, performers;
//! - [`clients`]: subscribers, sans-IO; [`stats`]: counters and histograms;
//! - [`record`]: recordings; [`synthetic`]: models and frames for bench and tests;
//! - [`arrival`]: when the processing thread polls instead of parking (a steady source's
//!   beat);
//! - [`net`]: sockets (large receive buffers, connected senders);
//! - `server`, `control`: the tasks, the only code that awaits; `processing`: the processing
//!   thread; `sender`: its fan-out to the subscribers.
//!
//! Entry points: [`run`] (bind, then serve until the token is cancelled), or [`bind`] then
//! [`Bound::run`] to learn the bound addresses first (tests bind `127.0.0.1:0`).

pub mod arrival;
mod command;
pub mod config;
mod control;
pub mod net;
mod processing;
pub mod record;
mod sender;
mod server;
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

/// Loads a model file on a blocking thread.
///
/// # Errors
/// Unreadable or invalid file, named.
pub async fn load_model(path: std::path::PathBuf) -> anyhow::Result<IcaModel> {
    tokio::task::spawn_blocking(move || crate::offline::load_model(&path))
        .await
        .context("model loader panicked")?
}
