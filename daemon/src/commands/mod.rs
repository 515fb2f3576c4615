//! One module per subcommand; [`run`] dispatches.

mod analyze;
mod bench;
mod convert;
mod demo;
mod edit;
mod info;
mod inspect;
mod project;
mod replay;
mod serve;
mod synth;
mod train;

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
        Command::Train(args) => train::run(&args),
        Command::Project(args) => project::run(&args),
        Command::Edit(args) => edit::run(&args),
        Command::Inspect(args) => inspect::run(&args),
        Command::Analyze(args) => analyze::run(&args),
        Command::Serve(args) => serve::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Replay(args) => replay::run(&args),
        Command::Demo(args) => demo::run(&args),
    }
}

/// Loads a take, naming the file in the error.
pub(crate) fn load_take(path: &std::path::Path) -> Result<::replay::Take> {
    crate::offline::load_take(path)
}

/// Loads and validates a model file, naming the file in the error.
pub(crate) fn load_model(path: &std::path::Path) -> Result<ica_core::model::IcaModel> {
    use anyhow::Context;
    let file = std::fs::File::open(path).with_context(|| format!("{}", path.display()))?;
    ica_core::model::IcaModel::load(std::io::BufReader::new(file))
        .with_context(|| format!("{}: not a valid model", path.display()))
}
