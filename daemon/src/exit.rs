//! Exit codes of the `emoshift` binary.
//!
//! | code | meaning |
//! |---|---|
//! | 0 | success |
//! | 1 | the command failed: bad input file, bad model, I/O error |
//! | 2 | usage error: unknown flag or bad value (printed by clap) |

/// Success.
pub const OK: u8 = 0;
/// The command failed on its input or environment.
pub const FAILURE: u8 = 1;
/// The command line itself was wrong.
pub const USAGE: u8 = 2;

/// The exit code for an error returned by a command.
pub fn code_for(err: &anyhow::Error) -> u8 {
    if err.downcast_ref::<UsageError>().is_some() {
        USAGE
    } else {
        FAILURE
    }
}

/// A command-line mistake found after parsing (e.g. a flag value that clap cannot check).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);

/// True when the error is stdout's reader going away (`emoshift info x | head`): not a failure.
/// serde_json's errors do not chain to their I/O error (`inspect --json | head`), so their
/// kind is asked for.
pub fn is_broken_pipe(err: &anyhow::Error) -> bool {
    use std::io::ErrorKind::BrokenPipe;
    err.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == BrokenPipe)
            || cause
                .downcast_ref::<serde_json::Error>()
                .is_some_and(|e| e.io_error_kind() == Some(BrokenPipe))
    })
}

#[cfg(test)]
mod tests;
