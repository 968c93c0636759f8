//! The bus tools: `servobus scan`, `ping`, `read`, `write` and `set-id`.

use std::process::ExitCode;

/// Arguments of `servobus scan`.
#[derive(Debug, clap::Args)]
pub struct ScanArgs {
    /// Serial port.
    #[arg(long)]
    pub port: String,
    /// Baud rate.
    #[arg(long, default_value_t = 1_000_000)]
    pub baud: u32,
    /// Try every baud rate of the servo baud table.
    #[arg(long, conflicts_with = "baud")]
    pub all_bauds: bool,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `servobus ping`.
#[derive(Debug, clap::Args)]
pub struct PingArgs {
    /// Serial port.
    #[arg(long)]
    pub port: String,
    /// Baud rate.
    #[arg(long, default_value_t = 1_000_000)]
    pub baud: u32,
    /// Servo ID.
    #[arg(long)]
    pub id: u8,
}

/// Arguments of `servobus read`.
#[derive(Debug, clap::Args)]
pub struct ReadArgs {
    /// Serial port.
    #[arg(long)]
    pub port: String,
    /// Baud rate.
    #[arg(long, default_value_t = 1_000_000)]
    pub baud: u32,
    /// Servo ID.
    #[arg(long)]
    pub id: u8,
    /// Register name, e.g. present_position.
    pub register: String,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `servobus write`.
#[derive(Debug, clap::Args)]
pub struct WriteArgs {
    /// Serial port.
    #[arg(long)]
    pub port: String,
    /// Baud rate.
    #[arg(long, default_value_t = 1_000_000)]
    pub baud: u32,
    /// Servo ID.
    #[arg(long)]
    pub id: u8,
    /// Register name, e.g. goal_position.
    pub register: String,
    /// Value to write.
    #[arg(allow_negative_numbers = true)]
    pub value: i64,
}

/// Arguments of `servobus set-id`.
#[derive(Debug, clap::Args)]
pub struct SetIdArgs {
    /// Serial port.
    #[arg(long)]
    pub port: String,
    /// Baud rate.
    #[arg(long, default_value_t = 1_000_000)]
    pub baud: u32,
    /// The servo's current ID.
    #[arg(long)]
    pub id: u8,
    /// The new ID.
    pub new_id: u8,
}

/// Runs `servobus scan`.
pub fn scan(_args: ScanArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!("servobus scan is not available yet")
}
/// Runs `servobus ping`.
pub fn ping(_args: PingArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!("servobus ping is not available yet")
}
/// Runs `servobus read`.
pub fn read(_args: ReadArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!("servobus read is not available yet")
}
/// Runs `servobus write`.
pub fn write(_args: WriteArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!("servobus write is not available yet")
}
/// Runs `servobus set-id`.
pub fn set_id(_args: SetIdArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!("servobus set-id is not available yet")
}
