//! `servobus`: the command line of the servobus runtime.
//!
//! Each subcommand lives in its own module under `cmd/`; this file only parses
//! the arguments and dispatches.

mod cmd;
mod record;

use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = cmd::Cli::parse();
    match cmd::run(cli) {
        Ok(code) => code,
        Err(err) => {
            eprintln!("error: {err:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
