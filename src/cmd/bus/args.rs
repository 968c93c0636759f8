//! The arguments of the bus tools: the port every one opens, and the
//! servo and register each single-servo tool takes.

/// Options every bus tool shares.
#[derive(Debug, clap::Args)]
pub struct PortArgs {
    /// Serial port (or the pty of `servobus sim`).
    #[arg(long)]
    pub port: String,
    /// The adapter's latency per transaction, in microseconds (default: the
    /// FTDI latency timer when the adapter is an FTDI one, else 1000).
    #[arg(long, value_name = "US", value_parser = crate::shared::args::latency_us_arg)]
    pub latency_us: Option<u64>,
}

/// Arguments of `servobus scan`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Two servos sharing an ID (their replies collide) is a problem found: exit 1."
)]
pub struct ScanArgs {
    /// Port and latency.
    #[command(flatten)]
    pub port: PortArgs,
    /// Baud rate (one of the servos' table: 1000000, 500000, ... 38400).
    #[arg(long, default_value_t = 1_000_000, value_parser = crate::shared::args::baud_arg)]
    pub baud: u32,
    /// Try every baud rate of the servo baud table.
    #[arg(long, conflicts_with = "baud")]
    pub all_bauds: bool,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Port, baud rate and servo: what every single-servo tool needs.
#[derive(Debug, clap::Args)]
pub struct ServoArgs {
    /// Port and latency.
    #[command(flatten)]
    pub port: PortArgs,
    /// Baud rate (one of the servos' table: 1000000, 500000, ... 38400).
    #[arg(long, default_value_t = 1_000_000, value_parser = crate::shared::args::baud_arg)]
    pub baud: u32,
    /// Servo ID (for set-id: the servo's current ID).
    #[arg(long)]
    pub id: u8,
}

/// Arguments of `servobus ping`.
#[derive(Debug, clap::Args)]
pub struct PingArgs {
    /// Port, baud rate and servo.
    #[command(flatten)]
    pub servo: ServoArgs,
}

/// Arguments of `servobus read`.
#[derive(Debug, clap::Args)]
pub struct ReadArgs {
    /// Port, baud rate and servo.
    #[command(flatten)]
    pub servo: ServoArgs,
    /// Register name, e.g. present_position (or its address).
    pub register: String,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `servobus write`.
#[derive(Debug, clap::Args)]
pub struct WriteArgs {
    /// Port, baud rate and servo.
    #[command(flatten)]
    pub servo: ServoArgs,
    /// Register name, e.g. goal_position (or its address).
    pub register: String,
    /// Value to write.
    #[arg(allow_negative_numbers = true)]
    pub value: i64,
}

/// Arguments of `servobus registers`.
#[derive(Debug, clap::Args)]
pub struct RegistersArgs {
    /// Only this series' table: sts (STS/SMS servos) or scs.
    #[arg(long, value_parser = ["sts", "scs"])]
    pub series: Option<String>,
}

/// Arguments of `servobus set-id`.
#[derive(Debug, clap::Args)]
pub struct SetIdArgs {
    /// Port, baud rate and servo.
    #[command(flatten)]
    pub servo: ServoArgs,
    /// The new ID.
    pub new_id: u8,
}
