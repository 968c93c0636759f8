//! `servobus sim`.

use std::process::ExitCode;

/// Arguments of `servobus sim`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The robot file whose servos to serve.
    #[arg(long)]
    pub robot: std::path::PathBuf,
    /// Make this path a symbolic link to the pty.
    #[arg(long)]
    pub link: Option<std::path::PathBuf>,
    /// Do not pace bytes at the wire rate.
    #[arg(long)]
    pub no_pacing: bool,
    /// Fault injection, e.g. `drop=0.01,corrupt=0.01,seed=7`.
    #[arg(long)]
    pub faults: Option<String>,
    /// Echo every request back, as a half-duplex adapter without direction control does.
    #[arg(long)]
    pub echo: bool,
}

/// Runs `servobus sim`.
pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("servobus sim is not available yet")
}
