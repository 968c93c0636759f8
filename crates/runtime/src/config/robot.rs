//! Robot files: buses, servos and joint limits.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::time::Duration;

use serde::Deserialize;
use servobus_protocol::registers::{self, model_by_name, Model, MODELS};
use servobus_protocol::MAX_ID;

use super::calibration::{Calibration, JointCalibration};
use super::error::{ConfigError, Source};
use super::locate::FieldPath;
use super::Units;

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
    /// file). `None`: identify it while the joints move ([`Lead::Auto`](crate::Lead::Auto)).
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
}

/// Whether a robot's angles go through a calibration.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum RobotCalibration {
    /// None asked for: angles are measured from each servo's middle tick
    /// with the robot file's `offset` and `inverted`.
    #[default]
    None,
    /// The robot file names a calibration file that does not exist yet: the
    /// robot runs on the simulator as designed, and refuses real servos.
    Missing(PathBuf),
    /// Loaded and applied: every joint maps through its calibration and its
    /// limits are clipped to the measured range.
    Applied {
        /// The calibration file.
        path: PathBuf,
        /// Its content.
        calibration: Calibration,
    },
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
    /// The adapter's latency per transaction.
    pub latency: Duration,
    /// The servos' return delay (register 7).
    pub return_delay: Duration,
    /// Wait for replies by polling the port without blocking (`busy_poll`
    /// in the robot file; default false): the control thread keeps its core
    /// and sees each reply without the kernel's wake-up latency.
    pub busy_poll: bool,
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
    /// Lowest position, in the robot's units.
    pub min: f64,
    /// Highest position, in the robot's units.
    pub max: f64,
    /// Velocity limit, units/s.
    pub max_velocity: f64,
    /// Acceleration limit, units/s^2.
    pub max_acceleration: f64,
    /// Jerk limit, units/s^3 (`None`: acceleration may step).
    pub max_jerk: Option<f64>,
    /// Servo angle (from the middle of its range) at joint position 0, units.
    pub offset: f64,
    /// The joint turns the opposite way to the servo.
    pub inverted: bool,
    /// Rest position, units.
    pub home: Option<f64>,
    /// The joint's calibration, when the robot has one: it replaces
    /// `offset` and `inverted` in the mapping to ticks.
    pub calibration: Option<JointCalibration>,
}

impl Robot {
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
}

impl BusConfig {
    /// The timing model of this bus's link.
    pub fn link(&self) -> servobus_timing::Link {
        servobus_timing::Link::new(self.baud).with_latency(self.latency)
    }
}

impl JointConfig {
    /// The rest position: `home`, or 0 clamped into the limits.
    pub fn rest(&self) -> f64 {
        self.home
            .unwrap_or_else(|| 0.0f64.clamp(self.min, self.max))
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRobot {
    name: String,
    #[serde(default)]
    units: Units,
    #[serde(default = "default_rate")]
    rate: f64,
    #[serde(default)]
    lead_ms: Option<f64>,
    #[serde(default)]
    calibration: Option<PathBuf>,
    #[serde(default)]
    calibration_pose: HashMap<String, f64>,
    buses: Vec<RawBus>,
}

fn default_rate() -> f64 {
    100.0
}

fn default_baud() -> u32 {
    1_000_000
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBus {
    name: String,
    #[serde(default)]
    port: Option<String>,
    #[serde(default = "default_baud")]
    baud: u32,
    #[serde(default)]
    latency_us: u64,
    #[serde(default)]
    return_delay_us: u64,
    #[serde(default)]
    busy_poll: bool,
    joints: Vec<RawJoint>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawJoint {
    name: String,
    id: i64,
    model: String,
    min: f64,
    max: f64,
    max_velocity: f64,
    max_acceleration: f64,
    #[serde(default)]
    max_jerk: Option<f64>,
    #[serde(default)]
    offset: f64,
    #[serde(default)]
    inverted: bool,
    #[serde(default)]
    home: Option<f64>,
}

/// The largest lag-compensation lead a robot file may set, ms.
const MAX_LEAD_MS: f64 = 500.0;

/// The largest return delay register 7 can hold (255 x 2 us).
const MAX_RETURN_DELAY_US: u64 = 510;

/// Loads and validates a robot file, including that its default rate fits
/// every bus.
///
/// # Errors
///
/// [`ConfigError::Read`] when the file cannot be read; otherwise
/// [`ConfigError::Invalid`] naming the file, line, column and field of the
/// first problem: YAML syntax, an unknown or missing field, a duplicate ID or
/// joint name, an ID above 253, an unknown model, `min >= max`, a
/// non-positive limit, a limit outside the servo's range, or a rate the bus
/// cannot carry (the error says which rate would fit).
pub fn load_robot(path: &Path) -> Result<Robot, ConfigError> {
    load_robot_calibrated(path, None)
}

/// Like [`load_robot`], with the calibration file `calibration` instead of
/// the one the robot file names (`--calibration`).
///
/// # Errors
/// As [`load_robot`], and the errors of [`load_calibration`] and of
/// applying it: a joint it lacks, another servo ID or model, a measured
/// range that leaves nothing of the joint's limits.
pub fn load_robot_calibrated(
    path: &Path,
    calibration: Option<&Path>,
) -> Result<Robot, ConfigError> {
    let (robot, source) = load_calibrated(path, calibration)?;
    check_rate(
        &robot,
        &source,
        robot.rate_hz,
        &FieldPath::root().key("rate"),
    )?;
    Ok(robot)
}

/// Like [`load_robot`], but accepts a default rate that does not fit (for
/// `servobus budget`, which reports what would fit instead).
///
/// # Errors
///
/// As [`load_robot`], less the rate check.
pub fn load_robot_any_rate(path: &Path) -> Result<Robot, ConfigError> {
    load(path).map(|(robot, _)| robot)
}

/// [`load_robot_any_rate`] with the calibration file `calibration` instead
/// of the one the robot file names (`--calibration`).
///
/// # Errors
/// As [`load_robot_calibrated`], less the rate check.
pub fn load_robot_any_rate_calibrated(
    path: &Path,
    calibration: Option<&Path>,
) -> Result<Robot, ConfigError> {
    load_calibrated(path, calibration).map(|(robot, _)| robot)
}

/// The robot as designed, without any calibration applied (what
/// `servobus calibrate` starts from), and the calibration file the robot
/// file names, if it names one.
///
/// # Errors
/// As [`load_robot_any_rate`].
pub fn load_robot_design(path: &Path) -> Result<(Robot, Option<PathBuf>), ConfigError> {
    let (robot, _, named) = load_design(path)?;
    Ok((robot, named))
}

pub(crate) fn load(path: &Path) -> Result<(Robot, Source), ConfigError> {
    load_calibrated(path, None)
}

/// Loads a robot file and applies its calibration (or `calibration`, which
/// takes precedence over the file's `calibration:`).
pub(crate) fn load_calibrated(
    path: &Path,
    calibration: Option<&Path>,
) -> Result<(Robot, Source), ConfigError> {
    let (robot, source, named) = load_design(path)?;
    let robot = match calibration.map(Path::to_owned).or(named) {
        Some(file) if calibration.is_some() || file.exists() => {
            super::calibrated::apply(robot, &file)?
        }
        Some(file) => Robot {
            calibration: RobotCalibration::Missing(file),
            ..robot
        },
        None => robot,
    };
    Ok((robot, source))
}

fn load_design(path: &Path) -> Result<(Robot, Source, Option<PathBuf>), ConfigError> {
    let source = Source::read(path)?;
    let raw: RawRobot = source.parse()?;
    let named = raw
        .calibration
        .as_ref()
        .map(|rel| path.parent().unwrap_or(Path::new("")).join(rel));
    let robot = validate(raw, &source)?;
    check_servo_range(&robot, &source)?;
    Ok((robot, source, named))
}

/// Checks that `rate_hz` fits every bus of `robot`; the error points at `field`.
pub(crate) fn check_rate(
    robot: &Robot,
    source: &Source,
    rate_hz: f64,
    field: &FieldPath,
) -> Result<(), ConfigError> {
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(source.error(field, format!("rate must be positive, got {rate_hz}")));
    }
    for bus in &robot.buses {
        if let Err(why) = super::budget::check_bus(bus, rate_hz) {
            return Err(source.error(field, format!("bus `{}`: {why}", bus.name)));
        }
    }
    Ok(())
}

fn positive(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

fn validate(raw: RawRobot, src: &Source) -> Result<Robot, ConfigError> {
    let root = FieldPath::root();
    if raw.name.trim().is_empty() {
        return Err(src.error(&root.key("name"), "must not be empty"));
    }
    if !positive(raw.rate) {
        return Err(src.error(
            &root.key("rate"),
            format!("must be a positive rate in Hz, got {}", raw.rate),
        ));
    }
    let lead = match raw.lead_ms {
        None => None,
        Some(ms) if ms.is_finite() && (0.0..=MAX_LEAD_MS).contains(&ms) => {
            Some(Duration::from_secs_f64(ms / 1e3))
        }
        Some(ms) => {
            return Err(src.error(
                &root.key("lead_ms"),
                format!("must be between 0 and {MAX_LEAD_MS} ms, got {ms}"),
            ))
        }
    };
    if raw.buses.is_empty() {
        return Err(src.error(&root.key("buses"), "a robot needs at least one bus"));
    }
    let pose = raw.calibration_pose;
    let mut bus_names = HashSet::new();
    let mut joint_names: HashMap<String, FieldPath> = HashMap::new();
    let mut buses = Vec::with_capacity(raw.buses.len());
    for (bi, rb) in raw.buses.into_iter().enumerate() {
        let bp = root.key("buses").index(bi);
        if !bus_names.insert(rb.name.clone()) {
            return Err(src.error(
                &bp.key("name"),
                format!("bus name `{}` is used twice", rb.name),
            ));
        }
        if registers::baud_index(rb.baud).is_none() {
            let valid: Vec<String> = (0..=u8::MAX)
                .map_while(registers::baud_rate)
                .map(|b| b.to_string())
                .collect();
            return Err(src.error(
                &bp.key("baud"),
                format!(
                    "{} baud is not a rate the servos can be set to; use one of {}",
                    rb.baud,
                    valid.join(", ")
                ),
            ));
        }
        if rb.return_delay_us > MAX_RETURN_DELAY_US || rb.return_delay_us % 2 != 0 {
            return Err(src.error(
                &bp.key("return_delay_us"),
                format!(
                    "must be an even number of microseconds from 0 to {MAX_RETURN_DELAY_US} \
                     (register 7 counts 2 us), got {}",
                    rb.return_delay_us
                ),
            ));
        }
        if rb.joints.is_empty() {
            return Err(src.error(&bp.key("joints"), "a bus needs at least one joint"));
        }
        let mut ids: HashMap<u8, usize> = HashMap::new();
        let mut joints = Vec::with_capacity(rb.joints.len());
        for (ji, rj) in rb.joints.into_iter().enumerate() {
            let jp = bp.key("joints").index(ji);
            let joint = validate_joint(rj, &jp, src)?;
            if let Some(first) = ids.insert(joint.id, ji) {
                return Err(src.error(
                    &jp.key("id"),
                    format!(
                        "ID {} is already used on bus `{}` by joint {}",
                        joint.id, rb.name, first
                    ),
                ));
            }
            if let Some(prev) = joint_names.insert(joint.name.clone(), jp.clone()) {
                return Err(src.error(
                    &jp.key("name"),
                    format!("joint name `{}` is already used at {prev}", joint.name),
                ));
            }
            joints.push(joint);
        }
        buses.push(BusConfig {
            name: rb.name,
            port: rb.port,
            baud: rb.baud,
            latency: Duration::from_micros(rb.latency_us),
            return_delay: Duration::from_micros(rb.return_delay_us),
            busy_poll: rb.busy_poll,
            joints,
        });
    }
    let mut robot = Robot {
        name: raw.name,
        units: raw.units,
        rate_hz: raw.rate,
        lead,
        buses,
        path: src.path.clone(),
        calibration: RobotCalibration::None,
        calibration_pose: Vec::new(),
    };
    robot.calibration_pose = calibration_pose(&robot, &pose, src)?;
    Ok(robot)
}

fn validate_joint(rj: RawJoint, jp: &FieldPath, src: &Source) -> Result<JointConfig, ConfigError> {
    if rj.name.trim().is_empty() {
        return Err(src.error(&jp.key("name"), "must not be empty"));
    }
    let id = match u8::try_from(rj.id) {
        Ok(id) if id <= MAX_ID => id,
        _ => {
            return Err(src.error(
                &jp.key("id"),
                format!("servo IDs go from 0 to {MAX_ID}, got {}", rj.id),
            ))
        }
    };
    let Some(model) = model_by_name(&rj.model) else {
        let known: Vec<&str> = MODELS.iter().map(|m| m.name).collect();
        return Err(src.error(
            &jp.key("model"),
            format!("unknown model `{}` (known: {})", rj.model, known.join(", ")),
        ));
    };
    for (field, v) in [("min", rj.min), ("max", rj.max), ("offset", rj.offset)] {
        if !v.is_finite() {
            return Err(src.error(&jp.key(field), "must be a finite number"));
        }
    }
    if rj.min >= rj.max {
        return Err(src.error(
            &jp.key("max"),
            format!("max ({}) must be greater than min ({})", rj.max, rj.min),
        ));
    }
    for (field, v) in [
        ("max_velocity", Some(rj.max_velocity)),
        ("max_acceleration", Some(rj.max_acceleration)),
        ("max_jerk", rj.max_jerk),
    ] {
        if let Some(v) = v {
            if !positive(v) {
                return Err(src.error(&jp.key(field), format!("must be positive, got {v}")));
            }
        }
    }
    let joint = JointConfig {
        name: rj.name,
        id,
        model,
        min: rj.min,
        max: rj.max,
        max_velocity: rj.max_velocity,
        max_acceleration: rj.max_acceleration,
        max_jerk: rj.max_jerk,
        offset: rj.offset,
        inverted: rj.inverted,
        home: rj.home,
        calibration: None,
    };
    if let Some(home) = joint.home {
        if !(home >= joint.min && home <= joint.max) {
            return Err(src.error(
                &jp.key("home"),
                format!("home {home} is outside [{}, {}]", joint.min, joint.max),
            ));
        }
    }
    Ok(joint)
}

/// The calibration pose in joint order: every joint named exists and its
/// angle is inside its limits; unnamed joints are at 0.
fn calibration_pose(
    robot: &Robot,
    pose: &HashMap<String, f64>,
    src: &Source,
) -> Result<Vec<f64>, ConfigError> {
    let field = FieldPath::root().key("calibration_pose");
    for (name, &v) in pose {
        let Some(joint) = robot.joint(name) else {
            return Err(src.key_error(&field.key(name), format!("no joint `{name}`")));
        };
        if !(v >= joint.min && v <= joint.max) {
            return Err(src.error(
                &field.key(name),
                format!("{v} is outside [{}, {}]", joint.min, joint.max),
            ));
        }
    }
    Ok(robot
        .joints()
        .map(|j| pose.get(&j.name).copied().unwrap_or(0.0))
        .collect())
}

/// Checks that both limits of every joint land inside the servo's tick range
/// (needs the robot's units, so it runs after the joint is built).
pub(crate) fn check_servo_range(robot: &Robot, src: &Source) -> Result<(), ConfigError> {
    let root = FieldPath::root();
    for (bi, bus) in robot.buses.iter().enumerate() {
        for (ji, joint) in bus.joints.iter().enumerate() {
            let map = super::JointMap::new(joint, robot.units);
            let jp = root.key("buses").index(bi).key("joints").index(ji);
            for (field, v) in [("min", joint.min), ("max", joint.max)] {
                let t = map.raw_ticks(robot.units.to_rad(v));
                if t < 0.0 || t > f64::from(joint.model.max_position()) {
                    let (lo, hi) = map.servo_range(robot.units);
                    return Err(src.error(
                        &jp.key(field),
                        format!(
                            "{v} {} is beyond what the {} can reach here: with offset {} \
                             and inverted {}, positions go from {lo:.1} to {hi:.1}",
                            robot.units, joint.model.name, joint.offset, joint.inverted
                        ),
                    ));
                }
            }
        }
    }
    Ok(())
}
