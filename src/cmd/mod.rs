//! Subcommands of the `servobus` binary.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Smooth, on-time motion for Feetech serial-bus servos.
#[derive(Debug, Parser)]
#[command(name = "servobus", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {}

/// Runs the parsed command line and returns the process exit code.
pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {}
}
