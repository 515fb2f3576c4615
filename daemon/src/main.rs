//! The `emoshift` binary: parses the command line and hands over to
//! [`daemon::commands::main_with`].

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    match daemon::cli::Cli::try_parse() {
        Ok(cli) => daemon::commands::main_with(cli),
        // --help and --version, and the help a bare `emoshift` gets.
        Err(e)
            if !e.use_stderr()
                || e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand =>
        {
            e.exit()
        }
        Err(e) => {
            eprintln!("emoshift: error: {}", daemon::cli::one_line(&e));
            ExitCode::from(2)
        }
    }
}
