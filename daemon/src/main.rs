//! The `emoshift` binary: parses the command line and hands over to
//! [`daemon::commands::main_with`].

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    daemon::commands::main_with(daemon::cli::Cli::parse())
}
