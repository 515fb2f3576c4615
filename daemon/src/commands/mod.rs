//! One module per subcommand; [`run`] dispatches.

mod convert;
mod info;
mod synth;

use anyhow::Result;

use crate::cli::{Cli, Command};

/// Runs the parsed command line.
///
/// # Errors
/// Whatever the command reports; the binary prints the chain on one line.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Synth(args) => synth::run(&args),
        Command::Info(args) => info::run(&args),
        Command::Convert(args) => convert::run(&args),
    }
}

/// Loads a take, naming the file in the error.
pub(crate) fn load_take(path: &std::path::Path) -> Result<replay::Take> {
    use anyhow::Context;
    replay::load(path).with_context(|| format!("{}", path.display()))
}
