//! The arguments of `servobus follow`: the follower, the leader, the
//! outputs and whose limits the follower keeps.

use std::path::PathBuf;
use std::time::Duration;

/// Arguments of `servobus follow`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The follower: robot file or built-in name, its port and calibration.
    #[command(flatten)]
    pub robot: crate::shared::flags::RobotArgs,
    /// `--write-servos`: store what the robot file asks of the servos'
    /// EEPROM before the run.
    #[command(flatten)]
    pub store: crate::shared::flags::WriteServosArg,
    /// Serial port of the leader arm (absent: a simulated leader).
    #[arg(long)]
    pub leader: Option<String>,
    /// The leader's robot file (default: the follower's).
    #[arg(long, value_parser = crate::shared::flags::robot_arg)]
    pub leader_robot: Option<PathBuf>,
    /// The leader's calibration file (default: its robot file's).
    #[arg(long)]
    pub leader_calibration: Option<PathBuf>,
    /// A scripted hand moving the simulated leader (`servobus sim --hand`
    /// format; built-in: so101-hand).
    #[arg(long, value_name = "H.yaml", value_parser = crate::shared::flags::hand_arg, conflicts_with = "leader")]
    pub leader_hand: Option<PathBuf>,
    /// Stop after this many seconds (default: run until Ctrl-C).
    #[arg(long, value_parser = crate::shared::args::run_seconds_arg)]
    pub seconds: Option<Duration>,
    /// Write one CSV row per cycle and joint of the follower (as play's).
    #[arg(long)]
    pub log: Option<PathBuf>,
    /// Draw the leader against the follower (.svg or .png).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Save the follower's commanded path as a recording `time_s,<joint>...`
    /// in degrees, which `servobus play TAKE.csv --robot ...` plays.
    #[arg(long, value_name = "TAKE.csv")]
    pub record: Option<PathBuf>,
    /// `--rerun FILE.rrd`, `--rerun-connect [ADDR]`: the follower in the
    /// Rerun viewer (measured, with its goals as a ghost).
    #[command(flatten)]
    pub rerun: crate::shared::flags::RerunArgs,
    /// Print the report as one JSON object (no live line).
    #[arg(long)]
    pub json: bool,
    /// The follower's speed, acceleration and jerk limits: `model`, what
    /// each servo's model can do (its top speed and fastest ramp), so that
    /// it keeps up with the leader the way raw goal writes do; or `robot`,
    /// the robot file's (gentler, for choreography). The robot file's
    /// position limits hold either way.
    #[arg(long, value_enum, default_value_t = FollowLimits::Model)]
    pub limits: FollowLimits,
}

/// Whose speed, acceleration and jerk limits the follower keeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FollowLimits {
    /// What each servo's model can do.
    Model,
    /// The robot file's.
    Robot,
}
