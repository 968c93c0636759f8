//! The flags several commands share: where a physical robot's servos are
//! ([`HardwareArgs`], [`RobotArgs`]), robot, motion, mounting and hand
//! arguments that take a built-in's name as well as a file, and the checks
//! of an output file made before anything moves.

use std::path::PathBuf;

/// `--port` and `--calibration`: where a physical robot's servos are and
/// how they are calibrated. A command whose flag means more says so with
/// `#[command(mut_arg(...))]` on its own arguments.
#[derive(Debug, Clone, clap::Args)]
pub struct HardwareArgs {
    /// Serial port of real servos, for the robot's first bus (default: the
    /// robot file's ports; without any, the built-in simulator).
    #[arg(long)]
    pub port: Option<String>,
    /// Calibration file of the physical robot (default: the robot file's
    /// `calibration:`).
    #[arg(long)]
    pub calibration: Option<PathBuf>,
}

/// `--robot` (required) and the [`HardwareArgs`] of the commands that work on
/// one robot's servos.
#[derive(Debug, Clone, clap::Args)]
pub struct RobotArgs {
    /// The robot file, or a built-in robot's name.
    #[arg(long = "robot", id = "robot", value_name = "ROBOT", value_parser = robot_arg)]
    pub path: PathBuf,
    /// Its port and calibration.
    #[command(flatten)]
    pub hardware: HardwareArgs,
}

/// `--write-servos` on the commands that run a robot (play, stream,
/// follow, serve).
#[derive(Debug, Clone, Copy, Default, clap::Args)]
pub struct WriteServosArg {
    /// On real servos: first store in their EEPROM what the robot file
    /// asks of them and they do not hold (each joint's operating mode, with
    /// the torque off; its `servo:` p, d, i, protection_current and
    /// max_temperature). Without it a run writes no EEPROM and refuses a
    /// servo in the wrong operating mode.
    #[arg(long)]
    pub write_servos: bool,
}

/// Parses a robot argument: a file, or a built-in robot's name.
pub(crate) fn robot_arg(arg: &str) -> Result<PathBuf, std::convert::Infallible> {
    Ok(servobus::builtin::robot_path_or_name(arg.as_ref()))
}

/// Parses a motion argument: a file, or a built-in motion's name.
pub(crate) fn motion_arg(arg: &str) -> Result<PathBuf, std::convert::Infallible> {
    Ok(servobus::builtin::motion_path_or_name(arg.as_ref()))
}

/// A rate that does not fit a bus, with the library's advice and this
/// command line's own switch for a round-robin read.
pub(crate) fn rate_advice(why: &servobus_config::RateError) -> String {
    let flag = if why.round_robin_helps() {
        " (for one run: --round-robin)"
    } else {
        ""
    };
    format!("{}{flag}", why.with_advice())
}

/// Parses a simulator mounting argument: a file, or a built-in's name.
pub(crate) fn mounting_arg(arg: &str) -> Result<PathBuf, std::convert::Infallible> {
    use servobus::builtin::{path_or_name, Kind};
    Ok(path_or_name(Kind::Mounting, arg.as_ref()))
}

/// Parses a simulator hand argument: a file, or a built-in's name.
pub(crate) fn hand_arg(arg: &str) -> Result<PathBuf, std::convert::Infallible> {
    use servobus::builtin::{path_or_name, Kind};
    Ok(path_or_name(Kind::Hand, arg.as_ref()))
}

/// Fails at once, before anything moves, when the plot `path` has an
/// extension other than `formats` (lower case, e.g. `["svg", "png"]`):
/// the file would not be what its name says. A path that is there and is
/// no regular file (`/dev/stdout`, a FIFO) takes the first format.
///
/// # Errors
/// An input error (exit 2) naming the formats.
pub(crate) fn check_plot_format(path: &std::path::Path, formats: &[&str]) -> anyhow::Result<()> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let special = std::fs::metadata(path).is_ok_and(|m| !m.is_file());
    if special || formats.contains(&ext.as_str()) {
        return Ok(());
    }
    let names: Vec<String> = formats
        .iter()
        .map(|f| format!("{} (.{f})", f.to_ascii_uppercase()))
        .collect();
    Err(crate::shared::exit::input(format!(
        "--plot {}: plots are written as {}; give one of those",
        path.display(),
        names.join(" or ")
    )))
}

/// Fails at once, before anything moves, when the file `path` given with
/// `flag` could not be written after the run: a directory, a missing
/// directory, a read-only file, a directory in which no file can be created
/// ([`servobus_robot::files::check_output`]). Nothing is created or changed: an
/// existing file stays as it is until the run's new one replaces it whole.
///
/// # Errors
/// An input error (exit 2) naming the flag and the file.
pub(crate) fn check_writable(flag: &str, path: &std::path::Path) -> anyhow::Result<()> {
    servobus_robot::files::check_output(path)
        .map_err(|e| crate::shared::exit::input(format!("{flag}: {e}; nothing was moved")))
}
