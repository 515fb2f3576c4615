//! The `emoshift` binary, built inside the tests package so end-to-end tests can spawn it
//! (`CARGO_BIN_EXE_emoshift-e2e`). Same code path as daemon/src/main.rs.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    daemon::commands::main_with(daemon::cli::Cli::parse())
}
