//! `servobus plan`.

use std::process::ExitCode;

/// Arguments of `servobus plan`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The motion file.
    pub motion: std::path::PathBuf,
    /// Robot file (default: the one the motion file names).
    #[arg(long)]
    pub robot: Option<std::path::PathBuf>,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Draw position and velocity of every joint over time (SVG).
    #[arg(long)]
    pub plot: Option<std::path::PathBuf>,
}

/// Runs `servobus plan`.
pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("servobus plan is not available yet")
}
