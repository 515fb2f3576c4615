//! The `emoshift` binary: parses the command line, installs tracing, runs the command and maps its
//! outcome to an exit code.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = daemon::cli::Cli::parse();
    let default_level = match cli.command {
        daemon::cli::Command::Demo(_) => "warn",
        _ => "info",
    };
    daemon::logging::install(default_level);
    match daemon::commands::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) if daemon::exit::is_broken_pipe(&err) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("emoshift: error: {err:#}");
            ExitCode::from(daemon::exit::code_for(&err))
        }
    }
}
