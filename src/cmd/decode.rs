//! `servobus decode`.

use std::process::ExitCode;

/// Arguments of `servobus decode`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Who sent the frames: the host (instructions) or a servo (status replies).
    #[arg(long, default_value = "host")]
    pub from: String,
    /// Frames in hex; spaces optional; several may be concatenated.
    #[arg(required = true)]
    pub hex: Vec<String>,
    /// Servo model whose register map names the addresses.
    #[arg(long, default_value = "sts3215")]
    pub model: String,
    /// Print one JSON object per packet or problem.
    #[arg(long)]
    pub json: bool,
}

/// Runs `servobus decode`.
pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("servobus decode is not available yet")
}
