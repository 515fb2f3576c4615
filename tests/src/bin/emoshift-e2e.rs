//! The `emoshift` binary, built inside the tests package so end-to-end tests can spawn it
//! (`CARGO_BIN_EXE_emoshift-e2e`). Same code path as daemon/src/main.rs.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = daemon::cli::Cli::parse();
    daemon::logging::install("info");
    match daemon::commands::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) if daemon::exit::is_broken_pipe(&err) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("emoshift: error: {err:#}");
            ExitCode::from(daemon::exit::code_for(&err))
        }
    }
}
