//! The `emoshift` binary's library: the frame engine, the offline logic, the live service, a
//! loopback harness and the commands, over the leaf crates `ica-core` (numerics), `protocol`
//! (wire formats) and `replay` (takes on disk, the synthetic face, the pacer).
//!
//! # Rooms
//!
//! ```text
//!                 ┌────────────┐
//!   main.rs ────▶ │  commands  │  thin: parse arguments, call a room, print
//!                 └──┬───┬───┬─┘
//!                    │   │   └──────────────────┐
//!                    ▼   ▼                      ▼
//!          ┌──────────┐ ┌──────────┐ ────▶ ┌──────────┐
//!          │ offline  │ │ loopback │       │  serve   │  tokio, sockets, threads, files
//!          └────┬─────┘ └────┬─────┘       └────┬─────┘
//!               │            │                  │
//!               └────────────┴──────▶ ┌─────────▼──┐
//!                                     │   engine   │  its own package: sans-IO, the
//!                                     └────────────┘  compiler keeps it so
//! ```
//!
//! Arrows point one way: nothing below knows what is above it (`scripts/check-modules`).
//! `docs/architecture.md` walks the frame path and the training path function by function.
//!
//! - [`engine`] (the `engine` package under `daemon/engine`): a source's frame in, the
//!   edited frame to every sink, without tokio, sockets, clock or files.
//! - [`offline`]: takes and models on disk, training preparation ([`offline::training`]),
//!   analysis ([`offline::analysis`]) and edit planning ([`offline::edit`]), as functions over
//!   takes and models. Numerics live in `ica-core`.
//! - [`serve`]: the live service around one [`engine::Pipeline`]: the sources
//!   ([`serve::sources`]), the processing thread, the sinks ([`serve::sinks`]), control, the
//!   monitor page; and `record`'s capture.
//! - [`loopback`]: one in-process harness (daemon, paced source, receiver, control client,
//!   synthetic models) for the demo, `emoshift bench` and the end-to-end tests.
//! - [`commands`]: one small module per subcommand; [`cli`] is their arguments.
//!
//! `main.rs` parses [`cli::Cli`] and calls [`commands::main_with`], which installs
//! [`logging`], runs the command and maps its error to an exit code ([`exit::code_for`]).
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod cli;
pub mod commands;
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
