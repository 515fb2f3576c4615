//! The `emoshift` binary: parses the command line and hands over to
//! [`daemon::commands::main_with`].

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    // A corrupt C3D can make c3dio panic; the reader catches that and decodes the file with
    // emoshift's own decoder, so the panic's message and backtrace are not the user's news.
    let speak = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if !replay::c3d::catching_c3dio_panic() {
            speak(info);
        }
    }));
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
