//! The emoshift front ends and service.
//!
//! `main.rs` stays thin: it parses [`cli::Cli`] and calls [`exit::main_with`], which installs
//! [`logging`], calls [`commands::run`] and maps the error to an exit code with
//! [`exit::code_for`]. Each subcommand is a small function in [`commands`] over the library
//! crates (`replay`, `ica-core`, `protocol`).
#![warn(missing_docs)]

pub mod cli;
pub mod commands;
pub mod engine;
pub mod exit;
pub mod logging;
pub mod loopback;
pub mod offline;
pub mod serve;

/// `println!` that returns the I/O error instead of panicking, so `emoshift info x | head` ends
/// quietly when the reader goes away (see [`exit::code_for`], which treats a broken pipe as
/// success). Use inside functions returning `anyhow::Result`.
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)?;
    }};
}
