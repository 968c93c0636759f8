//! Robot files: buses, servos and joint limits.
//!
//! Parts: the types and loaders here, `raw` (the file's shape as serde
//! reads it), `validate` (from that shape to a [`Robot`], every problem
//! located in the file), `servo` (a joint's mode and the `servo:`
//! settings, turned into register writes of its model) and `faults` (a
//! joint's own `faults:` policy).

mod base;
mod faults;
mod loading;
mod raw;
mod servo;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_faults;
#[cfg(test)]
mod tests_servo;
#[cfg(test)]
mod tests_urdf;
mod urdf;
mod validate;

use std::path::{Path, PathBuf};
use std::time::Duration;

use servobus_protocol::registers::Model;

use super::calibration::JointCalibration;
use super::error::{ConfigError, Source};
use super::Units;
pub use base::{BaseTarget, BaseTargetError, WheelTargets};
pub use faults::{FaultResponse, JointFaults};
use loading::{design_of, load_design, rate_fits, with_calibration};
pub(crate) use loading::{load_calibrated, require_calibration};
pub use servo::{JointMode, ServoSettings, ServoWrite};
pub(crate) use validate::{check_rate, check_servo_range};

/// A robot: its buses and the joints on each, as read from a robot file.
#[derive(Debug, Clone, PartialEq)]
pub struct Robot {
    /// The robot's name.
    pub name: String,
    /// The unit of every angle in [`JointConfig`].
    pub units: Units,
    /// Default control rate in Hz (a motion may override it).
    pub rate_hz: f64,
    /// Lag compensation: command the path this far ahead (`lead_ms` in the
    /// file). `None`: identify it while the joints move (the runtime's `Lead::Auto`).
    pub lead: Option<Duration>,
    /// The serial buses, each with its joints.
    pub buses: Vec<BusConfig>,
    /// The file it was loaded from (empty for robots built in code).
    pub path: PathBuf,
    /// The calibration of the physical robot, if the robot file names one
    /// (`calibration: FILE`) or one was given (`--calibration`).
    pub calibration: RobotCalibration,
    /// The pose a person holds the robot in while calibrating, per joint in
    /// the robot's joint order and units (`calibration_pose`; default 0).
    pub calibration_pose: Vec<f64>,
    /// The robot's geometry (`kinematics:`), checked against its joints;
    /// joint limits unset ([`Robot::geometry`] sets them).
    pub kinematics: Option<servobus_kinematics::Geometry>,
    /// The URDF the geometry was imported from (`kinematics: {urdf: FILE}`),
    /// kept for its links' visuals (meshes resolved relative to the URDF);
    /// `None` for geometry typed by hand, or none.
    pub urdf: Option<servobus_kinematics::Urdf>,
    /// The mobile base its wheel joints drive (`base:`), checked against
    /// its joints: every wheel of the base is a `mode: wheel` joint.
    pub base: Option<servobus_kinematics::Base>,
}

/// Whether a robot's angles go through a calibration.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum RobotCalibration {
    /// None asked for: angles are measured from each servo's middle tick
    /// with the robot file's `offset` and `inverted`.
    #[default]
    None,
    /// The robot file names a calibration file that does not exist yet.
    /// The simulator serves such a robot as designed (to be calibrated),
    /// but nothing plans or plays it: [`load_motion`](super::load_motion)
    /// and [`load_robot`] with [`RobotOptions::to_play`] refuse it, naming
    /// the file, and real servos are refused before they move.
    Missing(PathBuf),
    /// Loaded and applied: every joint maps through its calibration (held
    /// in [`JointConfig::calibration`]) and its limits are clipped to the
    /// measured range.
    Applied {
        /// The calibration file.
        path: PathBuf,
    },
    /// Loaded as designed ([`CalibrationChoice::Design`]): the robot file
    /// names this calibration file (which may or may not exist), and it was
    /// not applied.
    Unapplied(PathBuf),
}

impl RobotCalibration {
    /// The calibration file: the one applied, or the one the robot file
    /// names; `None` when there is neither.
    pub fn file(&self) -> Option<&Path> {
        match self {
            RobotCalibration::None => None,
            RobotCalibration::Missing(path)
            | RobotCalibration::Applied { path }
            | RobotCalibration::Unapplied(path) => Some(path),
        }
    }
}

/// One serial bus and the servos on it.
#[derive(Debug, Clone, PartialEq)]
pub struct BusConfig {
    /// The bus's name (unique within the robot).
    pub name: String,
    /// Serial port; `None` runs on the simulator unless `--port` is given.
    pub port: Option<String>,
    /// Baud rate, bits per second.
    pub baud: u32,
    /// The adapter's latency per transaction (0 with `latency_us: auto`
    /// until the run measures it).
    pub latency: Duration,
    /// `latency_us: auto` (the default): the run measures the adapter at
    /// start-up and keeps its reply deadlines just above what the link
    /// does. A number in the robot file wins.
    pub latency_auto: bool,
    /// The servos' return delay (register 7).
    pub return_delay: Duration,
    /// Wait for replies by polling the port without blocking (`busy_poll`
    /// in the robot file; default false): the control thread keeps its core
    /// and sees each reply without the kernel's wake-up latency.
    pub busy_poll: bool,
    /// Allow reading servos round-robin (`round_robin` in the robot file;
    /// default false): at a rate the full cycle does not fit, each cycle
    /// reads a subset of the servos. Without it such a rate is refused.
    pub round_robin: bool,
    /// The joints, in the order they are written and read each cycle.
    pub joints: Vec<JointConfig>,
}

/// One joint: a servo, its limits and how its angle maps to the servo's.
#[derive(Debug, Clone, PartialEq)]
pub struct JointConfig {
    /// The joint's name (unique within the robot).
    pub name: String,
    /// Servo ID on its bus (0..=253).
    pub id: u8,
    /// The servo model, which gives the resolution and register map.
    pub model: &'static Model,
    /// Position (the default) or wheel (`mode:` in the robot file).
    pub mode: JointMode,
    /// Lowest position, in the robot's units. Unused for wheels: 0.0.
    pub min: f64,
    /// Highest position, in the robot's units. Unused for wheels: 0.0.
    pub max: f64,
    /// Velocity limit, units/s (a wheel's top speed, at most what its model
    /// can turn at).
    pub max_velocity: f64,
    /// Acceleration limit, units/s^2 (a wheel's, of its speed).
    pub max_acceleration: f64,
    /// Jerk limit, units/s^3 (`None`: acceleration may step).
    pub max_jerk: Option<f64>,
    /// Servo angle (from the middle of its range) at joint position 0,
    /// units (0 for wheels).
    pub offset: f64,
    /// The joint turns the opposite way to the servo.
    pub inverted: bool,
    /// Rest position, units (never for wheels).
    pub home: Option<f64>,
    /// The joint's calibration, when the robot has one: it replaces
    /// `offset` and `inverted` in the mapping to ticks.
    pub calibration: Option<JointCalibration>,
    /// The settings written to the servo when a run connects (`servo:` in
    /// the robot file), checked against the model at load; `None` when the
    /// file gives none.
    pub servo: Option<ServoSettings>,
    /// What a stall or a following error of this joint does (`faults:` in
    /// the robot file); the default is the run-wide policy.
    pub faults: JointFaults,
}

/// How long the jerk limit of [`Robot::with_model_limits`] takes to reach
/// the acceleration limit, s. The servo itself has no jerk limit, and a
/// follower's stop from full speed is longer by the speed times half the
/// ramp: 20 ms keeps the physical motion's RMS jerk below that of raw goal
/// writes while a flick or a 2 Hz reversal is overrun by about two degrees
/// more than raw writes would, where 50 ms overran them by ten
/// (`python/bench/teleop.py --by-class` measures both).
pub const MODEL_JERK_RAMP_S: f64 = 0.02;

impl Robot {
    /// This robot with every joint's speed and acceleration limits at what
    /// its servo model can do ([`Model::fastest_profile`]) and its jerk
    /// limit reaching that acceleration in [`MODEL_JERK_RAMP_S`]: the
    /// limits of live following (`servobus follow`, the LeRobot plugin),
    /// which keeps up with a stream the way raw goal writes would. Joints
    /// whose model states no such profile keep the file's limits, and so do
    /// wheels: a wheel's speed target is followed as given, and its limits
    /// are the speed and acceleration the robot builder allows the base
    /// (loading already keeps them within what the model can do).
    pub fn with_model_limits(mut self) -> Robot {
        let units = self.units;
        let positions = self.buses.iter_mut().flat_map(|b| b.joints.iter_mut());
        for joint in positions.filter(|j| !j.is_wheel()) {
            if let Some((v, a)) = joint.model.fastest_profile() {
                joint.max_velocity = units.from_rad(v.to_radians());
                joint.max_acceleration = units.from_rad(a.to_radians());
                joint.max_jerk = Some(joint.max_acceleration / MODEL_JERK_RAMP_S);
            }
        }
        self
    }

    /// Every joint of every bus, in bus order then joint order. This order
    /// is the robot's joint order: keyframe vectors and trajectories use it.
    pub fn joints(&self) -> impl Iterator<Item = &JointConfig> + '_ {
        self.buses.iter().flat_map(|b| b.joints.iter())
    }

    /// Number of joints over all buses.
    pub fn joint_count(&self) -> usize {
        self.buses.iter().map(|b| b.joints.len()).sum()
    }

    /// Index (in the robot's joint order) of the joint called `name`.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints().position(|j| j.name == name)
    }

    /// The joint called `name`.
    pub fn joint(&self, name: &str) -> Option<&JointConfig> {
        self.joints().find(|j| j.name == name)
    }

    /// The robot's geometry with every joint's current limits (radians),
    /// ready for forward and inverse kinematics; `None` without a
    /// `kinematics:` section.
    pub fn geometry(&self) -> Option<servobus_kinematics::Geometry> {
        let mut model = self.kinematics.clone()?;
        for (i, j) in self.joints().enumerate() {
            model.set_limits(i, self.units.to_rad(j.min), self.units.to_rad(j.max));
        }
        Some(model)
    }
}

impl BusConfig {
    /// The timing model of this bus's link.
    pub fn link(&self) -> servobus_timing::Link {
        servobus_timing::Link::new(self.baud).with_latency(self.latency)
    }
}

impl JointConfig {
    /// The rest position: `home`, or 0 clamped into the limits (0 for a
    /// wheel: at rest, its speed).
    pub fn rest(&self) -> f64 {
        self.home
            .unwrap_or_else(|| 0.0f64.clamp(self.min, self.max))
    }

    /// Whether the joint is a wheel ([`JointMode::Wheel`]): its target is a
    /// speed and it has no position limits.
    pub fn is_wheel(&self) -> bool {
        self.mode == JointMode::Wheel
    }

    /// The register writes of the joint's `servo:` settings
    /// ([`ServoSettings::writes`]); none without them.
    pub fn servo_writes(&self) -> &[ServoWrite] {
        self.servo.as_ref().map_or(&[], ServoSettings::writes)
    }
}

/// Where a robot file's text comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RobotSource<'a> {
    /// A robot file on disk, or a built-in file's path
    /// (`<built-in>/robots/so101.yaml`, as
    /// [`robot_path_or_name`](crate::builtin::robot_path_or_name) gives).
    Path(&'a Path),
    /// A built-in robot, by name (`so101`, with or without `.yaml`).
    Builtin(&'a str),
    /// A robot file given as its text, called `name` in errors; a
    /// calibration file it names is relative to the current directory.
    Text {
        /// What errors call the text (`<text>`).
        name: &'a Path,
        /// The YAML text.
        text: &'a str,
    },
}

impl<'a> From<&'a Path> for RobotSource<'a> {
    fn from(path: &'a Path) -> Self {
        RobotSource::Path(path)
    }
}

impl<'a> From<&'a PathBuf> for RobotSource<'a> {
    fn from(path: &'a PathBuf) -> Self {
        RobotSource::Path(path)
    }
}

/// Which calibration a robot is loaded with.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum CalibrationChoice {
    /// The file the robot file names (`calibration:`), if it names one. A
    /// named file that does not exist yet leaves the robot
    /// [`RobotCalibration::Missing`].
    #[default]
    Named,
    /// This file instead of the one the robot file names (`--calibration`).
    File(PathBuf),
    /// None: the robot as designed (what calibrating starts from). The file
    /// the robot file names, if any, is kept in
    /// [`RobotCalibration::Unapplied`].
    Design,
}

/// How [`load_robot`] loads a robot. The default: the calibration the robot
/// file names, its default rate checked against every bus.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RobotOptions {
    /// The calibration applied.
    pub calibration: CalibrationChoice,
    /// Accept a default rate that does not fit every bus (for a report of
    /// what would fit, or a run that gives its own rate).
    pub any_rate: bool,
    /// The robot is about to play a motion or a recording: a calibration
    /// file the robot file names must exist, since the calibrated limits
    /// are what the path is kept within.
    pub to_play: bool,
}

impl RobotOptions {
    /// The calibration file `file` instead of the one the robot file names,
    /// when given; the named one when `None`.
    #[must_use]
    pub fn calibration(mut self, file: Option<&Path>) -> Self {
        self.calibration = file.map_or(CalibrationChoice::Named, |f| {
            CalibrationChoice::File(f.to_owned())
        });
        self
    }

    /// The robot as designed, no calibration applied, any rate accepted.
    #[must_use]
    pub fn design() -> Self {
        RobotOptions {
            calibration: CalibrationChoice::Design,
            any_rate: true,
            to_play: false,
        }
    }

    /// Accepts a default rate that does not fit every bus.
    #[must_use]
    pub fn any_rate(mut self) -> Self {
        self.any_rate = true;
        self
    }

    /// Requires a calibration file the robot file names to exist.
    #[must_use]
    pub fn to_play(mut self) -> Self {
        self.to_play = true;
        self
    }
}

/// Loads and validates a robot from `source` as `options` say: the one
/// entry point for robots, whatever they are read from.
///
/// ```no_run
/// use std::path::Path;
/// use servobus_config::{load_robot, RobotOptions, RobotSource};
///
/// let arm = load_robot(Path::new("configs/robots/so101.yaml"), &RobotOptions::default())?;
/// let built_in = load_robot(RobotSource::Builtin("so101"), &RobotOptions::default().any_rate())?;
/// let design = load_robot(&arm.path, &RobotOptions::design())?;
/// # Ok::<(), servobus_config::ConfigError>(())
/// ```
///
/// # Errors
///
/// [`ConfigError::Read`] when the file cannot be read (or no built-in robot
/// has the name); otherwise [`ConfigError::Invalid`] naming the file, line,
/// column and field of the first problem: YAML syntax, an unknown or missing
/// field, a duplicate ID or joint name, an ID above 253, an unknown model,
/// `min >= max`, a position joint without `min` or `max`, a wheel given
/// `min`, `max`, `home` or `offset` or a `max_velocity` above its model's top
/// speed, a `servo:` setting out of range or for a register its model lacks,
/// a non-positive limit, a limit outside the servo's range, a
/// rate the bus cannot carry (the error says which rate would fit; not with
/// [`RobotOptions::any_rate`]); the errors of
/// [`load_calibration`](super::load_calibration) and of applying it (a joint
/// it lacks, another servo ID or model, a measured range that leaves nothing
/// of the joint's limits); with [`RobotOptions::to_play`], a calibration file
/// the robot file names that does not exist.
pub fn load_robot<'a>(
    source: impl Into<RobotSource<'a>>,
    options: &RobotOptions,
) -> Result<Robot, ConfigError> {
    let (robot, source, named) = match source.into() {
        RobotSource::Path(path) => load_design(path)?,
        RobotSource::Builtin(name) => {
            let name = name.strip_suffix(".yaml").unwrap_or(name);
            load_design(&super::builtin_path(&format!("robots/{name}.yaml")))?
        }
        RobotSource::Text { name, text } => {
            let source = Source {
                path: name.to_owned(),
                text: text.to_owned(),
            };
            design_of(source, Path::new(""))?
        }
    };
    let (robot, source) = match &options.calibration {
        CalibrationChoice::Named => with_calibration(robot, source, named, None)?,
        CalibrationChoice::File(file) => {
            with_calibration(robot, source, named, Some(file.as_path()))?
        }
        CalibrationChoice::Design => {
            let calibration = named.map_or(RobotCalibration::None, RobotCalibration::Unapplied);
            let robot = Robot {
                calibration,
                ..robot
            };
            (robot, source)
        }
    };
    if options.to_play {
        require_calibration(&robot, &source)?;
    }
    if options.any_rate {
        return Ok(robot);
    }
    rate_fits(robot, &source)
}
