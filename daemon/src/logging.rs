//! Tracing subscriber for the binary: `RUST_LOG` is respected (default `info`, `warn` for the
//! demo, whose own summary says what the daemon's status lines would), to stderr. Every event
//! of emoshift has the target `emoshift`, so `RUST_LOG=emoshift=debug` selects them. Colour
//! only on a terminal, and never with `NO_COLOR` set.

use std::io::IsTerminal;

use tracing_subscriber::EnvFilter;

/// Installs the global subscriber once with `default` as the level when `RUST_LOG` is unset;
/// later calls are ignored.
pub fn install(default: &str) {
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(default));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(colour(
            std::io::stderr().is_terminal(),
            std::env::var_os("NO_COLOR"),
        ))
        .with_target(false)
        .try_init();
}

/// Colour when writing to a terminal, unless `NO_COLOR` is set to anything but empty
/// (<https://no-color.org>).
fn colour(terminal: bool, no_color: Option<std::ffi::OsString>) -> bool {
    terminal && no_color.is_none_or(|v| v.is_empty())
}

#[cfg(test)]
mod tests;
