//! `servobus bench`.

use std::process::ExitCode;

/// Arguments of `servobus bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The robot file (default: configs/robots/so101.yaml).
    #[arg(long)]
    pub robot: Option<std::path::PathBuf>,
    /// Serial port of real servos (default: the simulator on a pty).
    #[arg(long)]
    pub port: Option<String>,
    /// How long to measure, in seconds.
    #[arg(long, default_value_t = 5.0)]
    pub seconds: f64,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// Runs `servobus bench`.
pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("servobus bench is not available yet")
}
