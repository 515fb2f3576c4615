//! One module per subcommand; [`run`] dispatches.

mod analyze;
mod bench;
mod convert;
mod demo;
mod edit;
mod info;
mod inject;
mod inspect;
pub mod progress;
mod project;
mod record;
mod regions;
mod repair;
mod replay;
mod serve;
mod session;
mod synth;
mod train;

use anyhow::Result;

use crate::cli::{Cli, Command};
use crate::exit::{code_for, is_broken_pipe};

/// The whole `emoshift` program after argument parsing: install logging, run the command, print
/// an error as one line and map it to an exit code ([`crate::exit`]). Shared by the `emoshift`
/// binary and the copy the end-to-end tests build, so both behave the same.
pub fn main_with(cli: Cli) -> std::process::ExitCode {
    let default_level = match cli.command {
        Command::Demo(_) => "warn",
        _ => "info",
    };
    crate::logging::install(default_level);
    match run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(err) if is_broken_pipe(&err) => std::process::ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("emoshift: error: {err:#}");
            std::process::ExitCode::from(code_for(&err))
        }
    }
}

/// `1 take`, `2 takes`: a count and its noun.
pub(crate) fn count(n: usize, noun: &str) -> String {
    match n {
        1 => format!("1 {noun}"),
        _ => format!("{n} {noun}s"),
    }
}

/// Runs the parsed command line.
///
/// # Errors
/// Whatever the command reports; the binary prints the chain on one line.
pub fn run(cli: Cli) -> Result<()> {
    crate::offline::set_input_limit(cli.max_input_mb.saturating_mul(1 << 20));
    match cli.command {
        Command::Synth(args) => synth::run(&args),
        Command::Info(args) => info::run(&args),
        Command::Inject(args) => inject::run(&args),
        Command::Repair(args) => repair::run(&args),
        Command::Convert(args) => convert::run(&args),
        Command::Regions(args) => regions::run(&args),
        Command::Train(args) => train::run(&args),
        Command::Project(args) => project::run(&args),
        Command::Edit(args) => edit::run(&args),
        Command::Inspect(args) => inspect::run(&args),
        Command::Analyze(args) => analyze::run(&args),
        Command::Serve(args) => serve::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Replay(args) => replay::run(&args),
        Command::Record(args) => record::run(&args),
        Command::Session(args) => session::run(&args),
        Command::Demo(args) => demo::run(&args),
    }
}
