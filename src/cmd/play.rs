//! `servobus play`.

use std::process::ExitCode;

/// Arguments of `servobus play`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The motion file.
    pub motion: std::path::PathBuf,
    /// Robot file (default: the one the motion file names).
    #[arg(long)]
    pub robot: Option<std::path::PathBuf>,
    /// Serial port of real servos (default: the built-in simulator).
    #[arg(long)]
    pub port: Option<String>,
    /// Control rate in Hz (default: the motion's, else the robot's).
    #[arg(long)]
    pub rate: Option<f64>,
    /// Run the simulator in virtual time, as fast as the CPU allows.
    #[arg(long)]
    pub fast: bool,
    /// Print the report as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Write one CSV row per cycle and joint.
    #[arg(long)]
    pub log: Option<std::path::PathBuf>,
    /// Draw commanded vs measured positions (SVG or PNG).
    #[arg(long)]
    pub plot: Option<std::path::PathBuf>,
}

/// Runs `servobus play`.
pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("servobus play is not available yet")
}
