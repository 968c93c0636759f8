//! `servobus serve` in a build without the `zenoh` feature: the command is
//! not there, and saying how to get it beats clap's "unrecognized
//! subcommand". Hidden from `--help`, the man page and the completions,
//! which list what this build can do.

use std::ffi::OsString;
use std::process::ExitCode;

/// Whatever followed `serve` (`--help` included): none of it is read.
#[derive(Debug, clap::Args)]
#[command(disable_help_flag = true)]
pub struct Args {
    #[arg(
        num_args = 0..,
        trailing_var_arg = true,
        allow_hyphen_values = true,
        hide = true
    )]
    rest: Vec<OsString>,
}

/// The message of `servobus serve` in this build (exit 2).
pub const NEEDS_ZENOH: &str = "`servobus serve` (the robot as a Zenoh node) is not in this \
    build: it needs the `zenoh` feature. From a clone of servobus, install it with \
    `cargo install --path . --features zenoh` (or run `cargo run --release --features zenoh \
    -- serve ...`)";

/// Refuses, naming the feature and the command that builds it.
pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    Err(crate::shared::exit::input(NEEDS_ZENOH))
}
