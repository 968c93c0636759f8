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

/// What a Rerun flag says in a build without the feature.
#[cfg(not(feature = "rerun"))]
const NO_RERUN: &str =
    "this servobus was built without Rerun: cargo install --path . --features rerun";

/// Where a Rerun viewer started with `rerun` listens (the default of
/// `--rerun-connect`; `servobus_robot::rerun::DEFAULT_VIEWER`).
pub(crate) const RERUN_VIEWER: &str = "rerun+http://127.0.0.1:9876/proxy";

/// `--rerun FILE.rrd` and `--rerun-connect [ADDR]` on the commands that
/// move or plan a robot: the robot in 3D with its joints' series and its
/// events, for the Rerun viewer. In every build; a build without the
/// cargo feature `rerun` refuses them before anything moves.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct RerunArgs {
    /// Record the robot in 3D (measured, with the commanded pose as a
    /// ghost), every joint's series, the tool's or feet's paths and the
    /// faults for the Rerun viewer, in this file (`rerun FILE.rrd` opens
    /// it; written whole when the command ends). Needs a servobus built
    /// with `--features rerun`.
    #[arg(long, value_name = "FILE.rrd")]
    pub rerun: Option<PathBuf>,
    /// Stream the same to a running Rerun viewer (started with `rerun`)
    /// at ADDR [default: rerun+http://127.0.0.1:9876/proxy].
    #[arg(
        long,
        value_name = "ADDR",
        num_args = 0..=1,
        default_missing_value = RERUN_VIEWER,
        conflicts_with = "rerun"
    )]
    pub rerun_connect: Option<String>,
}

/// A recording for the Rerun viewer, when one was asked for (always none
/// in a build without the feature, which refuses the flags).
#[derive(Debug, Default)]
pub(crate) struct Recording {
    /// The recorder and what it writes to (`--rerun FILE` or the address).
    #[cfg(feature = "rerun")]
    recorder: Option<(servobus_robot::rerun::Recorder, String)>,
}

impl RerunArgs {
    /// Whether a recording is asked for.
    pub(crate) fn wanted(&self) -> bool {
        self.rerun.is_some() || self.rerun_connect.is_some()
    }

    /// Refuses, before anything moves, a recording that cannot be made: in
    /// a build without Rerun; a file that could not be written; a viewer's
    /// address that is not one, or where nothing listens.
    ///
    /// # Errors
    /// An input error (exit 2) naming the flag.
    pub(crate) fn check(&self) -> anyhow::Result<()> {
        if !self.wanted() {
            return Ok(());
        }
        #[cfg(not(feature = "rerun"))]
        return Err(crate::shared::exit::input(NO_RERUN));
        #[cfg(feature = "rerun")]
        match self.sink() {
            Some((sink, flag)) => sink.check().map_err(|e| rerun_error(&flag, e)),
            None => Ok(()),
        }
    }

    /// Starts the recording asked for of `robot`, angles in `units`
    /// (checked as [`RerunArgs::check`] does first).
    ///
    /// # Errors
    /// Those of [`RerunArgs::check`]; a recording that cannot be started.
    pub(crate) fn start(
        &self,
        robot: &servobus_config::Robot,
        units: servobus_config::Units,
    ) -> anyhow::Result<Recording> {
        self.check()?;
        #[cfg(feature = "rerun")]
        if let Some((sink, flag)) = self.sink() {
            let recorder = servobus_robot::rerun::Recorder::create(robot, units, &sink)
                .map_err(|e| rerun_error(&flag, e))?;
            let what = match &sink {
                servobus_robot::rerun::Sink::File(path) => path.display().to_string(),
                servobus_robot::rerun::Sink::Viewer(address) => format!("the viewer at {address}"),
            };
            return Ok(Recording {
                recorder: Some((recorder, what)),
            });
        }
        let _ = (robot, units);
        Ok(Recording::default())
    }

    /// The sink asked for, and the flag that asked.
    #[cfg(feature = "rerun")]
    fn sink(&self) -> Option<(servobus_robot::rerun::Sink, String)> {
        use servobus_robot::rerun::Sink;
        match (&self.rerun, &self.rerun_connect) {
            (Some(path), _) => Some((
                Sink::File(path.clone()),
                format!("--rerun {}", path.display()),
            )),
            (None, Some(address)) => Some((
                Sink::Viewer(address.clone()),
                format!("--rerun-connect {address}"),
            )),
            (None, None) => None,
        }
    }
}

/// A recorder's error as the command line says it: what the user gave
/// (exit 2) or what failed (exit 1), naming the flag.
#[cfg(feature = "rerun")]
fn rerun_error(flag: &str, e: servobus_robot::rerun::RerunError) -> anyhow::Error {
    use servobus_robot::rerun::RerunError;
    match e {
        RerunError::Output(_) | RerunError::Address { .. } | RerunError::NoViewer { .. } => {
            crate::shared::exit::input(format!("{flag}: {e}; nothing was moved"))
        }
        other => anyhow::Error::new(other).context(flag.to_owned()),
    }
}

#[cfg_attr(not(feature = "rerun"), allow(unused_variables, clippy::unused_self))]
impl Recording {
    /// Takes a message of a run's telemetry in.
    pub(crate) fn telemetry(&mut self, message: &servobus_robot::Telemetry) {
        #[cfg(feature = "rerun")]
        if let Some((r, _)) = &mut self.recorder {
            r.telemetry(message);
        }
    }

    /// Records why the command stopped before or while it moved (a
    /// refusal, an error), at the latest time logged.
    pub(crate) fn refused(&mut self, error: &anyhow::Error) {
        #[cfg(feature = "rerun")]
        if let Some((r, _)) = &mut self.recorder {
            let text = crate::shared::exit::message(error);
            r.event(None, servobus_robot::rerun::Level::Error, &text);
        }
    }

    /// Goes on with what `started` gave, or, when it is an error (a run
    /// refused, say), records it as the last event, finishes the recording
    /// (kept: it shows what was refused; a failure to write it is said on
    /// stderr) and returns the error.
    ///
    /// # Errors
    /// `started`'s.
    pub(crate) fn unless_refused<T>(
        mut self,
        started: anyhow::Result<T>,
    ) -> anyhow::Result<(T, Recording)> {
        match started {
            Ok(value) => Ok((value, self)),
            Err(e) => {
                self.refused(&e);
                if let Err(failed) = self.finish() {
                    crate::shared::exit::report(&failed);
                }
                Err(e)
            }
        }
    }

    /// Records the state at `time_s` (see `Recorder::pose`).
    pub(crate) fn pose(
        &mut self,
        time_s: f64,
        commanded: &[Option<f64>],
        measured: &[Option<f64>],
    ) {
        #[cfg(feature = "rerun")]
        if let Some((r, _)) = &mut self.recorder {
            r.pose(time_s, commanded, measured);
        }
    }

    /// Records a planned path, sampled at `rate_hz`.
    pub(crate) fn plan(&mut self, trajectory: &servobus_robot::Trajectory, rate_hz: f64) {
        #[cfg(feature = "rerun")]
        if let Some((r, _)) = &mut self.recorder {
            r.plan(trajectory, rate_hz);
        }
    }

    /// Ends the recording: what it went to (a file, a viewer), or `None`
    /// when none was asked for.
    ///
    /// # Errors
    /// The recording could not be written or sent whole.
    pub(crate) fn finish(self) -> anyhow::Result<Option<String>> {
        #[cfg(feature = "rerun")]
        if let Some((r, what)) = self.recorder {
            r.finish()
                .map_err(|e| anyhow::Error::new(e).context("--rerun"))?;
            return Ok(Some(what));
        }
        Ok(None)
    }
}

#[cfg(all(test, feature = "rerun"))]
mod tests {
    #[test]
    fn the_default_viewer_is_the_recorder_s() {
        assert_eq!(super::RERUN_VIEWER, servobus_robot::rerun::DEFAULT_VIEWER);
    }
}
