//! The arguments of `servobus play`: the motion, the robot and where it
//! runs, the rate and scheduling, and the outputs.

use std::path::PathBuf;

/// Arguments of `servobus play`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The motion file (or a built-in motion's name, `servobus list`), or a
    /// recorded path (.csv: a `play --log` file or `time_s,<joint>...` in
    /// degrees; needs --robot).
    #[arg(value_parser = crate::shared::flags::motion_arg)]
    pub motion: PathBuf,
    /// Robot file or built-in name (default: the one the motion file names).
    #[arg(long, value_parser = crate::shared::flags::robot_arg)]
    pub robot: Option<PathBuf>,
    /// The port of real servos and their calibration.
    #[command(flatten)]
    pub hardware: crate::shared::flags::HardwareArgs,
    /// `--write-servos`: store what the robot file asks of the servos'
    /// EEPROM before the run.
    #[command(flatten)]
    pub store: crate::shared::flags::WriteServosArg,
    /// Control rate in Hz (default: the motion's, else the robot's).
    #[arg(long, value_parser = crate::shared::args::rate_arg)]
    pub rate: Option<f64>,
    /// Allow a rate above the maximum by reading servos round-robin (a
    /// subset each cycle), as `round_robin: true` on every bus.
    #[arg(long)]
    pub round_robin: bool,
    /// Run the simulator in virtual time, as fast as the CPU allows.
    #[arg(long, conflicts_with = "port")]
    pub fast: bool,
    /// Print the report as one JSON object (and no progress on stdout).
    #[arg(long)]
    pub json: bool,
    /// Write one CSV row per cycle and joint.
    #[arg(long)]
    pub log: Option<PathBuf>,
    /// `--rerun FILE.rrd`, `--rerun-connect [ADDR]`: the run in the Rerun
    /// viewer.
    #[command(flatten)]
    pub rerun: crate::shared::flags::RerunArgs,
    /// Draw planned vs measured positions and the tracking error: SVG
    /// (.svg) or PNG (.png); any other extension is refused before moving.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Wait for replies by polling the port without blocking, on every bus
    /// (as `busy_poll: true` in the robot file): saves the kernel's wake-up
    /// latency on each reply at the cost of a busy core per bus.
    #[arg(long, conflicts_with = "fast")]
    pub busy_poll: bool,
    /// Pin the control thread of the first bus to this core (the next bus
    /// to the next core, and so on).
    #[arg(long)]
    pub core: Option<usize>,
    /// Run the control threads under SCHED_FIFO at this priority (1..=99);
    /// where not permitted, a warning and normal scheduling.
    #[arg(long, value_parser = clap::value_parser!(i32).range(1..=99))]
    pub fifo: Option<i32>,
    /// Show the live servo view of `servobus monitor` while playing, from
    /// the run's telemetry (no extra bus traffic). Needs a terminal: refused
    /// (exit 2) before anything moves without one.
    #[arg(long, conflicts_with_all = ["json", "log", "plot", "rerun", "rerun_connect"])]
    pub monitor: bool,
    /// Start the simulated joints at these angles instead of their rest
    /// positions (robot units, robot joint order, comma-separated, e.g.
    /// `--sim-pose=30,-60,70,10,40,50`): the run approaches the first
    /// keyframe from there, as on real servos.
    #[arg(
        long,
        value_delimiter = ',',
        allow_negative_numbers = true,
        conflicts_with = "port"
    )]
    pub sim_pose: Option<Vec<f64>>,
    /// Tell every robot serving in this Zenoh group (`servobus serve
    /// --group NAME`) to play the motion together, instead of playing it
    /// here.
    #[cfg(feature = "zenoh")]
    #[arg(long, value_name = "NAME")]
    pub zenoh_group: Option<String>,
    /// With --zenoh-group: when the robots start, from now (`2s`, `500ms`).
    #[cfg(feature = "zenoh")]
    #[arg(long, default_value = "2s", requires = "zenoh_group", value_parser = crate::shared::args::duration_arg)]
    pub start_in: std::time::Duration,
    /// With --zenoh-group: a robot's endpoint to connect to (repeatable),
    /// e.g. tcp/127.0.0.1:7447.
    #[cfg(feature = "zenoh")]
    #[arg(long, value_name = "ENDPOINT", requires = "zenoh_group")]
    pub connect: Vec<String>,
}
