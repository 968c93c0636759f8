//! `servobus budget`.

use std::process::ExitCode;

/// Arguments of `servobus budget`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The robot file.
    #[arg(long)]
    pub robot: std::path::PathBuf,
    /// Control rate in Hz (default: the robot's).
    #[arg(long)]
    pub rate: Option<f64>,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// Runs `servobus budget`.
pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("servobus budget is not available yet")
}
