//! `emoshift serve`: config file + flags → [`Config`], a tokio runtime, Ctrl-C/SIGTERM turned
//! into one cancellation token, then [`crate::serve::run`]. Exits 0 after a clean shutdown.

use anyhow::{Context, Result};
use tokio_util::sync::CancellationToken;

use crate::cli::ServeArgs;
use crate::exit::UsageError;
use crate::serve::config::RawConfig;
use crate::serve::Config;

/// Reads the config file (if any) and lays the flags over it, then validates once.
///
/// # Errors
/// Unreadable file, unknown key, bad value (named).
pub(crate) fn config(args: &ServeArgs) -> Result<Config> {
    let mut raw = match &args.config {
        Some(path) => {
            let text =
                replay::file::read_to_string_bounded(path, replay::file::DEFAULT_MAX_TEXT_BYTES)?;
            RawConfig::from_toml(&text)
                .map_err(|e| UsageError(format!("{}: {e}", path.display())))?
        }
        None => RawConfig::default(),
    };
    if let Some(m) = &args.model {
        raw.model = Some(m.clone());
    }
    if let Some(r) = args.passthrough_rate {
        raw.passthrough_rate_hz = Some(r);
    }
    if let Some(l) = &args.listen {
        raw.listen = Some(l.clone());
    }
    if let Some(c) = &args.control {
        raw.control = Some(c.clone());
    }
    if !args.send.is_empty() {
        raw.send = args.send.clone();
    }
    if !args.control_allow.is_empty() {
        raw.control_allow = Some(args.control_allow.clone());
    }
    if !args.frames_allow.is_empty() {
        raw.frames_allow = Some(args.frames_allow.clone());
    }
    if let Some(l) = args.lowpass {
        raw.lowpass_s = Some(l);
    }
    natnet_flags(args, &mut raw);
    if let Some(m) = &args.monitor {
        raw.monitor = Some(m.clone());
    }
    if let Some(q) = &args.qtm_server {
        raw.qtm_server = Some(q.clone());
    }
    if let Some(q) = &args.qtm {
        raw.qtm = Some(q.clone());
    }
    raw.validate().map_err(|e| UsageError(e.to_string()).into())
}

/// The NatNet flags (the source's `--natnet*`, the server's `--natnet-server*`) over their
/// keys.
fn natnet_flags(args: &ServeArgs, raw: &mut RawConfig) {
    let flags = args.natnet_options.raw(args.natnet.clone());
    for (flag, key) in [
        (flags.server, &mut raw.natnet),
        (flags.data, &mut raw.natnet_data),
        (flags.interface, &mut raw.natnet_interface),
        (flags.timecode_rate, &mut raw.natnet_timecode_rate),
        (flags.names, &mut raw.natnet_names),
    ] {
        if flag.is_some() {
            *key = flag;
        }
    }
    for (flag, key) in [
        (&args.natnet_server, &mut raw.natnet_server),
        (
            &args.natnet_server_multicast,
            &mut raw.natnet_server_multicast,
        ),
        (
            &args.natnet_server_interface,
            &mut raw.natnet_server_interface,
        ),
        (&args.natnet_server_version, &mut raw.natnet_server_version),
    ] {
        if flag.is_some() {
            key.clone_from(flag);
        }
    }
    if args.natnet_server_raw {
        raw.natnet_server_raw = Some(true);
    }
}

pub(crate) fn run(args: &ServeArgs) -> Result<()> {
    let config = config(args)?;
    for warning in config.exposure_warnings() {
        tracing::warn!(target: "emoshift", "{warning}");
    }
    if config.model.is_none() && config.performers.iter().all(|p| p.model.is_none()) {
        tracing::warn!(
            target: "emoshift",
            rate_hz = config.passthrough_rate_hz,
            "no model: frames pass through unedited (recording works); load one with /model/load \
             PATH, or `emoshift session ... --load-into {}`",
            config.control
        );
    }
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("starting the tokio runtime")?;
    runtime.block_on(async move {
        let shutdown = CancellationToken::new();
        let bound = crate::serve::bind(config).await?;
        tracing::info!(
            target: "emoshift",
            frames = %bound.frame_addr()?,
            control = %bound.control_addr()?,
            "serving"
        );
        tokio::spawn(cancel_on_signal(shutdown.clone()));
        bound.run(shutdown).await
    })?;
    // Anything still blocking (a stuck send) must not hold the exit past the 1 s budget.
    runtime.shutdown_timeout(std::time::Duration::from_millis(200));
    Ok(())
}

/// Cancels `token` on Ctrl-C or SIGTERM.
pub(crate) async fn cancel_on_signal(token: CancellationToken) {
    signalled().await;
    tracing::info!(target: "emoshift", "shutting down");
    token.cancel();
}

/// Returns on Ctrl-C or SIGTERM.
pub(crate) async fn signalled() {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{signal, SignalKind};
        match signal(SignalKind::terminate()) {
            Ok(mut term) => {
                tokio::select! {
                    _ = tokio::signal::ctrl_c() => {}
                    _ = term.recv() => {}
                }
            }
            Err(_) => {
                let _ = tokio::signal::ctrl_c().await;
            }
        }
    }
    #[cfg(not(unix))]
    let _ = tokio::signal::ctrl_c().await;
}
