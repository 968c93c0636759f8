//! Motion files: poses, keyframes, timing and repetition.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::error::{ConfigError, Source};
use super::limits::check_segments;
use super::locate::FieldPath;
use super::motion_keyframes::{KeyframeBuilder, RawKeyframe};
use super::motion_poses::{PoseList, Resolver};
use super::robot::{self, Robot};
use super::spatial::Context;
use super::Units;

/// A choreography, resolved against its robot: every keyframe holds a
/// position for every joint of the robot.
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    /// The motion file.
    pub path: PathBuf,
    /// The robot file used (the motion's `robot:`, or the override).
    pub robot_path: PathBuf,
    /// The unit of every angle in this motion's keyframes (`deg` unless the
    /// file says otherwise, whatever the robot's unit).
    pub units: Units,
    /// The motion's own control rate, Hz, if it sets one.
    pub rate_hz: Option<f64>,
    /// Joint names in the robot's joint order (the order of
    /// [`Keyframe::positions`]).
    pub joints: Vec<String>,
    /// The keyframes of one repetition; the first is the start (t = 0).
    pub keyframes: Vec<Keyframe>,
    /// How many times the keyframes are played (at least 1). Between
    /// repetitions the path moves from the last keyframe back to the first
    /// (untimed) unless they are equal; `at` times count from the arrival at
    /// the repetition's first keyframe.
    pub repeat: u32,
    /// What the planner does when a timed segment would exceed a limit.
    pub on_limit: OnLimit,
    /// The path shape between timed keyframes.
    pub interpolation: Interpolation,
}

/// One keyframe, every joint resolved.
#[derive(Debug, Clone, PartialEq)]
pub struct Keyframe {
    /// Time from the start of the repetition, s; `None`: as soon as the
    /// limits allow.
    pub at: Option<f64>,
    /// Whether `at` was chosen by the planner rather than written in the
    /// file: a keyframe before a move in space is timed at its quickest
    /// arrival.
    pub planned_at: bool,
    /// The pose's name when the keyframe names one.
    pub pose: Option<String>,
    /// Whether the keyframe gives a tool pose (`tool:`, its joints solved
    /// from it).
    pub tool: bool,
    /// Position of every robot joint (robot joint order), in the motion's units.
    pub positions: Vec<f64>,
    /// The grasps the keyframe makes (its `grasp:`: the joint closes
    /// towards its `min` on the way here) and ends (a grasping joint its
    /// pose names).
    pub grasps: Vec<KeyframeGrasp>,
    /// 1-based line of the keyframe in the motion file.
    pub line: usize,
    /// 1-based column of the keyframe in the motion file.
    pub column: usize,
}

/// A grasp a keyframe makes or ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeyframeGrasp {
    /// The joint, in the robot's joint order.
    pub joint: usize,
    /// The effort, percent of the servo's torque; `None`: the grasp ends.
    pub effort: Option<f64>,
}

/// What to do when timed keyframes ask more than a joint's limits allow.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
#[serde(expecting = "`error` or `stretch`")]
pub enum OnLimit {
    /// Refuse the motion, naming the keyframe, joint, peak and limit.
    #[default]
    Error,
    /// Stretch the timing of the offending segments until the limits hold.
    Stretch,
}

/// The path shape through timed keyframes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
#[serde(expecting = "`shape_preserving`, `spline`, `monotone` or `quintic`")]
pub enum Interpolation {
    /// Shape-preserving, jerk-limited segments (the default): every joint
    /// stays within the range of the two keyframes around each segment and
    /// passes a keyframe where it turns back at zero speed; a motion that
    /// could stop at every keyframe on time is always accepted.
    #[default]
    #[serde(alias = "shape-preserving")]
    ShapePreserving,
    /// C2 cubic spline (`spline` or `cubic`), at rest at both ends; the
    /// smoothest, but it may overshoot the keyframes and is refused where
    /// it breaks a limit.
    #[serde(alias = "spline")]
    Cubic,
    /// Monotone cubic: never overshoots between keyframes.
    Monotone,
    /// Quintic (minimum-jerk) segments, at rest at every keyframe.
    #[serde(alias = "minimum_jerk", alias = "min_jerk")]
    Quintic,
}

impl Interpolation {
    /// The name a motion file uses for it.
    pub fn name(self) -> &'static str {
        match self {
            Interpolation::ShapePreserving => "shape_preserving",
            Interpolation::Cubic => "spline",
            Interpolation::Monotone => "monotone",
            Interpolation::Quintic => "quintic",
        }
    }
}

impl Motion {
    /// The path shape used: the interpolation's name when a keyframe after
    /// the first has a time, else `untimed` (time-optimal pass-through).
    pub fn path_shape(&self) -> &'static str {
        if self.keyframes.iter().skip(1).any(|k| k.at.is_some()) {
            self.interpolation.name()
        } else {
            "untimed"
        }
    }

    /// The control rate to use: the motion's, else the robot's.
    pub fn rate_hz(&self, robot: &Robot) -> f64 {
        self.rate_hz.unwrap_or(robot.rate_hz)
    }

    /// Where keyframe `index` sits, as `file:line:column`.
    pub fn keyframe_location(&self, index: usize) -> String {
        match self.keyframes.get(index) {
            Some(k) => format!("{}:{}:{}", self.path.display(), k.line, k.column),
            None => self.path.display().to_string(),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(
    expecting = "a motion file: a mapping with `keyframes:` and optional `robot:`, `poses:`, `repeat:`, ..."
)]
struct RawMotion {
    #[serde(default)]
    robot: Option<String>,
    #[serde(default)]
    units: Units,
    #[serde(default)]
    rate: Option<f64>,
    #[serde(default)]
    poses: PoseList,
    keyframes: Vec<RawKeyframe>,
    #[serde(default = "one")]
    repeat: i64,
    #[serde(default)]
    on_limit: OnLimit,
    #[serde(default)]
    interpolation: Interpolation,
}

fn one() -> i64 {
    1
}

/// Loads a motion file and its robot, and validates both together.
///
/// The robot is the motion's `robot:` path, taken relative to the motion
/// file, unless `robot_override` is given. Joints a keyframe does not name
/// keep their previous value; in the first keyframe they start at their
/// `home` (or 0 clamped into the limits). A keyframe's `tool: {xyz, pitch,
/// roll}` puts the robot's `tool` frame there by inverse kinematics from
/// the pose before it (after the keyframe's own `pose`, if it has one).
///
/// # Errors
///
/// [`ConfigError`] naming the file, line, column and field of the first
/// problem in either file: syntax, unknown fields, an unknown pose or joint,
/// a keyframe outside a joint's limits, a tool pose the arm cannot take
/// (unreachable, a limit, a singularity), times that do not increase, or a
/// rate the robot's buses cannot carry.
pub fn load_motion(
    path: &Path,
    robot_override: Option<&Path>,
) -> Result<(Motion, Robot), ConfigError> {
    load_motion_calibrated(path, robot_override, None)
}

/// Like [`load_motion`], with the calibration file `calibration` instead of
/// the one the robot file names (`--calibration`).
///
/// # Errors
/// As [`load_motion`] and [`load_robot`](super::load_robot).
pub fn load_motion_calibrated(
    path: &Path,
    robot_override: Option<&Path>,
    calibration: Option<&Path>,
) -> Result<(Motion, Robot), ConfigError> {
    load_motion_source(Source::read(path)?, robot_override, calibration)
}

/// Loads a motion given as YAML `text` (a message, a form): the same
/// checks as [`load_motion_calibrated`], its errors naming `name` with the
/// line and column in the text. A `robot:` path in it is taken relative to
/// `name`'s directory (the current one for a bare name such as `<text>`).
///
/// # Errors
/// As [`load_motion_calibrated`]; [`ConfigError::TooLarge`] for a text
/// longer than a motion file may be.
pub fn load_motion_text(
    name: &Path,
    text: &str,
    robot_override: Option<&Path>,
    calibration: Option<&Path>,
) -> Result<(Motion, Robot), ConfigError> {
    load_motion_source(Source::text(name, text)?, robot_override, calibration)
}

/// Loads a motion from `src`: its robot, its poses and its keyframes.
fn load_motion_source(
    src: Source,
    robot_override: Option<&Path>,
    calibration: Option<&Path>,
) -> Result<(Motion, Robot), ConfigError> {
    let raw: RawMotion = src.parse()?;
    let root = FieldPath::root();
    let robot_path = robot_path(&src, &raw, robot_override)?;
    let robot = motion_robot(&src, &raw, &robot_path, robot_override, calibration)?;
    let repeat = check_repeat(&src, &raw, &robot)?;
    let resolver = Resolver {
        src: &src,
        robot: &robot,
        units: raw.units,
    };
    for (name, pose) in &raw.poses.0 {
        resolver.check_pose(pose, &root.key("poses").key(name), None)?;
    }
    if raw.keyframes.is_empty() {
        return Err(src.error(
            &root.key("keyframes"),
            "a motion needs at least one keyframe",
        ));
    }
    let spatial = Context {
        src: &src,
        robot: &robot,
        units: raw.units,
        interpolation: raw.interpolation,
        on_limit: raw.on_limit,
        body: None,
        repeat: u64::from(repeat),
    };
    let mut builder = KeyframeBuilder::new(&raw.poses, spatial, raw.keyframes.len());
    for (i, rk) in raw.keyframes.iter().enumerate() {
        builder.add(&root.key("keyframes").index(i), i, rk)?;
    }
    let keyframes = builder.finish();
    // Spatial keyframes add samples: the plan must still fit.
    if let Err(e) = check_segments(keyframes.len(), u64::from(repeat), robot.joint_count()) {
        return Err(src.error(&root.key("keyframes"), e.to_string()));
    }
    let motion = Motion {
        path: src.path.clone(),
        robot_path,
        units: raw.units,
        rate_hz: raw.rate,
        joints: robot.joints().map(|j| j.name.clone()).collect(),
        keyframes,
        repeat,
        on_limit: raw.on_limit,
        interpolation: raw.interpolation,
    };
    Ok((motion, robot))
}

/// The robot file the motion uses: `robot_override`, else the motion's
/// `robot:` (relative to the motion file, or a built-in robot).
fn robot_path(
    src: &Source,
    raw: &RawMotion,
    robot_override: Option<&Path>,
) -> Result<PathBuf, ConfigError> {
    match (robot_override, &raw.robot) {
        (Some(p), _) => Ok(p.to_owned()),
        (None, Some(robot)) => Ok(super::builtin::motion_robot_path(&src.path, robot)),
        (None, None) => Err(src.error(
            &FieldPath::root(),
            "no robot: add `robot: FILE` (relative to this file) or a built-in robot's name \
             (`robot: so101`)",
        )),
    }
}

/// Loads the robot at `robot_path` with its calibration, and checks that it
/// is calibrated and that its buses carry the motion's rate (or its own).
fn motion_robot(
    src: &Source,
    raw: &RawMotion,
    robot_path: &Path,
    robot_override: Option<&Path>,
    calibration: Option<&Path>,
) -> Result<Robot, ConfigError> {
    let root = FieldPath::root();
    let (robot, robot_src) =
        robot::load_calibrated(robot_path, calibration).map_err(|e| match e {
            // The robot the motion names cannot be read: point at the
            // `robot:` line, which is what to fix. (Another file that cannot
            // be read, a calibration, speaks for itself.)
            ConfigError::Read { ref path, .. } | ConfigError::TooLarge { ref path, .. }
                if robot_override.is_none() && *path == robot_path =>
            {
                src.error(
                    &root.key("robot"),
                    format!(
                        "{e}; fix this `robot:` (a file relative to this motion file, or a \
                         built-in robot: {}) or pass --robot",
                        super::builtin::names(super::builtin::Kind::Robot)
                    ),
                )
            }
            e => e,
        })?;
    robot::require_calibration(&robot, &robot_src)?;
    match raw.rate {
        Some(rate) => robot::check_rate(&robot, src, rate, &root.key("rate"))?,
        None => robot::check_rate(&robot, &robot_src, robot.rate_hz, &root.key("rate"))?,
    }
    Ok(robot)
}

/// The motion's `repeat`, checked: at least 1, and few enough that the
/// keyframes of every repetition fit a plan.
fn check_repeat(src: &Source, raw: &RawMotion, robot: &Robot) -> Result<u32, ConfigError> {
    let field = FieldPath::root().key("repeat");
    if raw.repeat < 1 {
        return Err(src.error(&field, format!("must be at least 1, got {}", raw.repeat)));
    }
    let repeat = u64::try_from(raw.repeat).unwrap_or(u64::MAX);
    if let Err(e) = check_segments(raw.keyframes.len(), repeat, robot.joint_count()) {
        return Err(src.error(&field, e.to_string()));
    }
    // At most MAX_PLANNED_SEGMENTS: it fits.
    Ok(u32::try_from(repeat).unwrap_or(u32::MAX))
}
