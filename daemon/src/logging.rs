//! Tracing subscriber for the binary: `RUST_LOG` is respected (default `info`, `warn` for the
//! demo, whose own summary says what the daemon's status lines would), to stderr.

use tracing_subscriber::EnvFilter;

/// Installs the global subscriber once with `default` as the level when `RUST_LOG` is unset;
/// later calls are ignored.
pub fn install(default: &str) {
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(default));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_target(false)
        .try_init();
}
