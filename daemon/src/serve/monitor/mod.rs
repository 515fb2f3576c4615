//! The monitor page (`serve --monitor 127.0.0.1:9080`): one page from the binary itself (plain
//! HTML, CSS and ES modules in `daemon/web/`, no CDN, no build step), over HTTP and one
//! WebSocket per page, served by axum on the daemon's tokio runtime.
//!
//! - [`Feed`] (processing thread): after each frame, one atomic load while no page is open;
//!   with a page open, the engine's [`MonitorTap`](engine::monitor::MonitorTap)
//!   decimates each stream to 30 Hz and the snapshot is swapped onto the [`Board`] with a
//!   `try_lock` (never waiting on the page's side);
//! - `hub`: wakes on the board, encodes each fresh snapshot once (`wire`) and hands it to every
//!   page's bounded queue: a slow page loses frames (counted), never grows a queue; sends the
//!   health (`status`) four times a second;
//! - `socket`: one page's WebSocket: the feed out, control messages in. Controls are OSC
//!   messages, exactly as the control socket takes them, through the same guard (allow-list,
//!   secret) and the same `control::execute`, so a page and an OSC client
//!   never disagree;
//! - `access`: loopback by default; beyond loopback (or with `monitor_token` set) a token,
//!   given once as `?token=` and then kept in a cookie; Host and Origin checked;
//! - `http`: the routes, the embedded files and their security headers (its `gate` and
//!   `secure` keep `emoshift session`'s performer page to the same rules).

pub(crate) mod access;
mod board;
pub(crate) mod http;
mod hub;
mod socket;
mod status;
mod wire;

pub use board::{Board, Feed};

use std::net::SocketAddr;
use std::sync::{Arc, Mutex};

use anyhow::{Context, Result};
use tokio::net::TcpListener;
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;

use super::control::ControlCtx;
use super::stats::Stats;

/// The address `--monitor` takes when given without one.
pub const DEFAULT_MONITOR: &str = "127.0.0.1:9080";
/// Pages open at once, at most; more are refused (503) and counted.
pub const MAX_VIEWERS: usize = 8;
/// Binds the monitor's listener (so a bad address fails at start, and tests learn the port).
///
/// # Errors
/// The address cannot be bound.
pub(crate) async fn bind(addr: SocketAddr) -> Result<TcpListener> {
    TcpListener::bind(addr)
        .await
        .with_context(|| format!("binding the monitor page {addr}"))
}

/// What the monitor's tasks share.
#[derive(Debug)]
pub(crate) struct Monitor {
    pub(crate) board: Arc<Board>,
    pub(crate) hub: Arc<hub::Hub>,
    pub(crate) access: access::Access,
    pub(crate) ctx: ControlCtx,
    pub(crate) stats: Arc<Mutex<Stats>>,
    pub(crate) shutdown: CancellationToken,
}

/// Serves the page on `listener` until shutdown: the HTTP server and the hub, on `tracker`.
/// Prints the page's URL once (with the token when one is needed).
///
/// # Errors
/// The listener has no address.
pub(crate) fn spawn(
    listener: TcpListener,
    token: Option<String>,
    (board, ctx, stats): (Arc<Board>, ControlCtx, Arc<Mutex<Stats>>),
    tracker: &TaskTracker,
    shutdown: CancellationToken,
) -> Result<()> {
    let addr = listener.local_addr()?;
    let access = access::Access::new(addr, token);
    announce(addr, &access);
    let hub = Arc::new(hub::Hub::new(Arc::clone(&board)));
    let monitor = Arc::new(Monitor {
        board,
        hub: Arc::clone(&hub),
        access,
        ctx,
        stats,
        shutdown: shutdown.clone(),
    });
    tracker.spawn(hub::run(Arc::clone(&monitor)));
    tracker.spawn(http::serve(listener, monitor));
    Ok(())
}

/// The URL an operator opens, printed once on stdout (the token is not logged).
fn announce(addr: SocketAddr, access: &access::Access) {
    let host = match addr.ip() {
        ip if ip.is_unspecified() => format!("<this host>:{}", addr.port()),
        _ => addr.to_string(),
    };
    let query = access
        .token()
        .map(|t| format!("?token={t}"))
        .unwrap_or_default();
    println!("monitor: http://{host}/{query}");
    tracing::info!(target: "emoshift", %addr, token = access.token().is_some(), "monitor page served");
}
