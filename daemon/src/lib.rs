//! The emoshift front ends and service.
//!
//! `main.rs` stays thin: it parses [`cli::Cli`], installs [`logging`], calls [`commands::run`] and
//! maps the error to an exit code with [`exit::code_for`]. Each subcommand is a small function in
//! [`commands`] over the library crates (`replay`, `ica-core`, `protocol`).
#![warn(missing_docs)]

pub mod cli;
pub mod commands;
pub mod exit;
pub mod logging;
