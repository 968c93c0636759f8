//! From a validated motion to a trajectory: units to radians, keyframe
//! times, repeat and options, and planner errors located in the motion file.

use servobus_trajectory::{
    self as traj, JointLimits, PlanError, PlanOptions, Quantity, TimedShape, Trajectory,
};

use super::limits::check_length;
use super::plan_terms::{peak_and_limit, plan_reason, quantity_unit};
use super::{ConfigError, Interpolation, Motion, OnLimit, Robot, Units};

/// Per-joint limits of `robot` in radians, in the robot's joint order.
pub fn joint_limits(robot: &Robot) -> Vec<JointLimits> {
    let u = robot.units;
    robot
        .joints()
        .map(|j| {
            JointLimits::new(
                u.to_rad(j.max_velocity),
                u.to_rad(j.max_acceleration),
                j.max_jerk.map(|x| u.to_rad(x)),
            )
            .with_positions(u.to_rad(j.min), u.to_rad(j.max))
        })
        .collect()
}

/// The trajectory planner's keyframes and options for `motion`, in radians.
pub fn plan_input(motion: &Motion) -> (Vec<traj::Keyframe>, PlanOptions) {
    let u = motion.units;
    let kfs = &motion.keyframes;
    let place = |k: usize| kfs.get(k).map(|kf| (kf.line, kf.column));
    let keyframes = kfs
        .iter()
        .enumerate()
        .map(|(i, k)| {
            let kf =
                traj::Keyframe::new(k.positions.iter().map(|&p| u.to_rad(p)).collect::<Vec<_>>());
            let kf = match k.at {
                Some(at) => kf.at(at),
                None => kf,
            };
            // Keyframes that share a place in the file are the samples of
            // one spatial keyframe (a line, a walk, a body move).
            let here = place(i);
            let sample = here == place(i + 1) || (i > 0 && here == place(i - 1));
            if sample {
                kf.shape(SAMPLE_SHAPE)
            } else {
                kf
            }
        })
        .collect();
    let options = plan_options(motion.interpolation, motion.on_limit, motion.repeat);
    (keyframes, options)
}

/// The interpolation of the dense samples of a spatial keyframe (a tool
/// line, a walk, a body move; they share the keyframe's line and column):
/// a C2 spline through them, which follows a smooth path sampled densely
/// far more closely than segments that could each stop on time.
pub(crate) const SAMPLE_SHAPE: TimedShape = TimedShape::Cubic;

/// The planner's options for a motion's `interpolation`, `on_limit` and
/// `repeat`.
pub(crate) fn plan_options(
    interpolation: Interpolation,
    on_limit: OnLimit,
    repeat: u32,
) -> PlanOptions {
    PlanOptions {
        shape: match interpolation {
            Interpolation::ShapePreserving => TimedShape::ShapePreserving,
            Interpolation::Cubic => TimedShape::Cubic,
            Interpolation::Monotone => TimedShape::Monotone,
            Interpolation::Quintic => TimedShape::MinimumJerk,
        },
        on_limit: match on_limit {
            OnLimit::Error => traj::OnLimit::Error,
            OnLimit::Stretch => traj::OnLimit::Stretch,
        },
        repeat,
        ..PlanOptions::default()
    }
}

/// Plans `motion` on `robot`: the path the scheduler samples, in radians.
///
/// # Errors
///
/// [`ConfigError::Invalid`] at the offending keyframe of the motion file
/// when the planner refuses: which joint, which quantity, the peak the
/// timing asks for and the limit, in the motion's units.
pub fn plan_motion(motion: &Motion, robot: &Robot) -> Result<Trajectory, ConfigError> {
    let limits = joint_limits(robot);
    let (keyframes, options) = plan_input(motion);
    let trajectory =
        traj::plan(&limits, &keyframes, &options).map_err(|e| locate_plan_error(motion, &e))?;
    check_motion_length(motion, &trajectory, motion.rate_hz(robot))?;
    Ok(trajectory)
}

/// Checks that `trajectory`, planned from `motion`, played at `rate_hz`
/// is within [`MAX_MOTION_DURATION_S`](super::limits::MAX_MOTION_DURATION_S)
/// and [`MAX_MOTION_CYCLES`](super::limits::MAX_MOTION_CYCLES) (`play
/// --rate` checks again at its own rate).
///
/// # Errors
/// [`ConfigError::Invalid`] at the first keyframe the motion reaches past
/// a limit, saying the limit.
pub fn check_motion_length(
    motion: &Motion,
    trajectory: &Trajectory,
    rate_hz: f64,
) -> Result<(), ConfigError> {
    let Err(e) = check_length(trajectory.duration(), rate_hz) else {
        return Ok(());
    };
    let keyframe = trajectory
        .segments()
        .iter()
        .find(|s| check_length(s.end, rate_hz).is_err())
        .map_or(0, |s| s.keyframe);
    let (line, column) = motion
        .keyframes
        .get(keyframe)
        .map_or((1, 1), |k| (k.line, k.column));
    Err(ConfigError::invalid(
        &motion.path,
        line,
        column,
        format!("keyframes[{keyframe}]"),
        format!("the motion is too long: {e}"),
    ))
}

/// `value` (rad-based, divided by s^order) in the motion's units.
fn in_units(units: Units, rad: f64) -> f64 {
    units.from_rad(rad)
}

/// The index in the file of the motion's keyframe `k`: a keyframe in space
/// is several samples that share its place.
fn file_index(motion: &Motion, k: usize) -> usize {
    let place = |kf: &super::Keyframe| (kf.line, kf.column);
    motion
        .keyframes
        .iter()
        .take(k)
        .zip(motion.keyframes.iter().skip(1))
        .filter(|(a, b)| place(a) != place(b))
        .count()
}

/// Turns a planner error into one pointing at the keyframe in the motion file.
fn locate_plan_error(motion: &Motion, e: &PlanError) -> ConfigError {
    let (keyframe, field, reason) = describe_plan_error(motion, e);
    let (line, column) = motion
        .keyframes
        .get(keyframe)
        .map_or((1, 1), |kf| (kf.line, kf.column));
    // Fields name the file's keyframe, not the sample.
    let field = field.replacen(
        &format!("keyframes[{keyframe}]"),
        &format!("keyframes[{}]", file_index(motion, keyframe)),
        1,
    );
    ConfigError::invalid(&motion.path, line, column, field, reason)
}

/// A planner error in the motion's terms: the keyframe (of the motion, a
/// sample index) it is about, the field there and the reason.
fn describe_plan_error(motion: &Motion, e: &PlanError) -> (usize, String, String) {
    let joint_name = |j: usize| motion.joints.get(j).map_or("?", String::as_str);
    let u = motion.units;
    match *e {
        PlanError::LimitExceeded {
            keyframe,
            joint,
            quantity,
            peak,
            limit,
        } => (
            keyframe,
            format!("keyframes[{keyframe}]"),
            limit_reason(u, joint_name(joint), quantity, peak, limit),
        ),
        PlanError::TooSoon {
            keyframe,
            needed,
            available,
        } => (
            keyframe,
            format!("keyframes[{keyframe}].at"),
            format!(
                "reaching this keyframe takes at least {needed:.3} s within the limits, but its \
                 time leaves {available:.3} s; move `at` later or set `on_limit: stretch`"
            ),
        ),
        PlanError::OutOfRange {
            keyframe, joint, ..
        }
        | PlanError::NotFinite { keyframe, joint } => (
            keyframe,
            format!("keyframes[{keyframe}].pose.{}", joint_name(joint)),
            format!("keyframe {keyframe}: {}", plan_reason(e, &motion.joints, u)),
        ),
        PlanError::TimeNotIncreasing {
            keyframe,
            at,
            previous,
        } => (
            keyframe,
            format!("keyframes[{keyframe}]"),
            format!(
                "{at} s is not after the keyframe before it, reached at {previous:.3} s (a tool \
                 line, walk or body move takes the time its speeds need)"
            ),
        ),
        PlanError::WrongJointCount { keyframe, .. } => {
            (keyframe, format!("keyframes[{keyframe}]"), e.to_string())
        }
        _ => (
            0,
            String::new(),
            format!("cannot plan: {}", plan_reason(e, &motion.joints, u)),
        ),
    }
}

/// Why a segment breaks `joint`'s limit on `quantity` (`peak` and `limit`
/// rad-based), in units `u`, with what to do about it.
fn limit_reason(u: Units, joint: &str, quantity: Quantity, peak: f64, limit: f64) -> String {
    let unit = quantity_unit(u, quantity);
    let hint = if quantity == Quantity::Position {
        "; the spline overshoots: add a keyframe, or leave `interpolation` out for the \
         default shape-preserving path"
    } else {
        "; give the segment more time, or set `on_limit: stretch`"
    };
    let (peak, limit) = peak_and_limit(in_units(u, peak), in_units(u, limit));
    format!(
        "joint `{joint}`: the segment arriving here needs a peak {quantity} of {peak} {unit}, \
         above the limit {limit} {unit}{hint}"
    )
}
