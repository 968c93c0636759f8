//! What a planned motion does, as figures: its duration, each joint's peaks
//! and range, its segments, and (for robots with geometry) what it does in
//! space. One type for every front end: `servobus plan --json` prints it,
//! the Python bindings read it, and a program can serialise it as it is.
//!
//! ```no_run
//! use servobus_robot::{summary::PlanSummary, Robot};
//!
//! let robot = Robot::open("so101")?;
//! let motion = robot.motion("arm-wave")?;
//! let path = robot.plan(&motion)?;
//! let summary = PlanSummary::new(&motion, robot.config(), &path, motion.units);
//! for joint in &summary.joints {
//!     println!("{}: peak {:.1}/s", joint.name, joint.peak_velocity);
//! }
//! # Ok::<(), servobus_robot::Error>(())
//! ```

use serde::Serialize;
use servobus_config::{spatial_summary, Motion, Robot, SpatialSummary, Units};
use servobus_trajectory::{JointState, Trajectory};

/// One joint of a plan, in the summary's units (per s, s², s³).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JointPeaks {
    /// The joint's name.
    pub name: String,
    /// The highest speed along the path.
    pub peak_velocity: f64,
    /// The highest acceleration along the path.
    pub peak_acceleration: f64,
    /// The highest jerk; `None` where the acceleration steps (a joint
    /// without a jerk limit).
    pub peak_jerk: Option<f64>,
    /// The lowest position along the path.
    pub min_position: f64,
    /// The highest position along the path.
    pub max_position: f64,
    /// Time the joint spends moving, s (sampled at the control rate).
    pub moving_s: f64,
}

/// One segment of a plan: the arrival at a keyframe of a repetition.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Segment {
    /// The keyframe arrived at (its index in the motion's keyframes).
    pub keyframe: usize,
    /// The repetition (0 for the first pass).
    pub repetition: usize,
    /// When the segment starts, s from the path's start.
    pub start_s: f64,
    /// When it ends (the keyframe is reached), s.
    pub end_s: f64,
}

/// What a motion does in space, for robots with geometry.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpaceFigures {
    /// The joint that comes closest to a limit.
    pub closest_limit_joint: Option<String>,
    /// How close it comes, in the summary's units.
    pub closest_limit: Option<f64>,
    /// The arm's tool: its peak speed, mm/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tool_peak_speed_mm_s: Option<f64>,
    /// The tool's path length, mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tool_path_mm: Option<f64>,
    /// The smallest dexterity along the path, mm/rad (0 at a singular
    /// pose).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_dexterity_mm_per_rad: Option<f64>,
    /// The feet: the highest lift, mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_foot_lift_mm: Option<f64>,
    /// How far the body travels, mm, from the feet on the ground.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub body_distance_mm: Option<f64>,
    /// How far the body turns, in the summary's units.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub body_turn: Option<f64>,
    /// The worst stability margin while feet are lifted, mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_stability_margin_mm: Option<f64>,
    /// When the margin first drops under 10 mm, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub low_margin_at_s: Option<Vec<f64>>,
}

impl SpaceFigures {
    /// The figures of `s`, angles in `units`.
    fn new(s: &SpatialSummary, units: Units) -> Self {
        SpaceFigures {
            body_distance_mm: s.feet.as_ref().and_then(|f| f.distance_mm),
            body_turn: s
                .feet
                .as_ref()
                .and_then(|f| f.turn_rad)
                .map(|t| units.from_rad(t)),
            closest_limit_joint: s.closest_limit.as_ref().map(|(j, _)| j.clone()),
            closest_limit: s.closest_limit.as_ref().map(|(_, g)| *g),
            tool_peak_speed_mm_s: s.tool.as_ref().map(|t| t.peak_speed_mm_s),
            tool_path_mm: s.tool.as_ref().map(|t| t.path_mm),
            min_dexterity_mm_per_rad: s.tool.as_ref().map(|t| t.min_dexterity),
            max_foot_lift_mm: s.feet.as_ref().map(|f| f.max_lift_mm),
            min_stability_margin_mm: s.feet.as_ref().and_then(|f| f.min_margin_mm),
            low_margin_at_s: s.feet.as_ref().map(|f| f.low_margins_s.clone()),
        }
    }
}

/// A planned motion's figures (see the module documentation). Serialised,
/// it is the object `servobus plan --json` prints.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlanSummary {
    /// The motion file (or `<built-in>/…` name).
    pub motion: String,
    /// The robot file the motion was planned for.
    pub robot: String,
    /// The units of every angle here (`deg`, `rad`).
    pub units: String,
    /// The control rate the path is sampled at, Hz.
    pub rate_hz: f64,
    /// Path shape: `untimed` (time-optimal pass-through), or the timed
    /// keyframes' interpolation (`shape_preserving`, `spline`, ...).
    pub interpolation: &'static str,
    /// How long the path lasts, s.
    pub duration_s: f64,
    /// Each joint of the motion, in its order.
    pub joints: Vec<JointPeaks>,
    /// Each segment of the path, in time order.
    pub segments: Vec<Segment>,
    /// What the motion does in space ([`PlanSummary::of_motion`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spatial: Option<SpaceFigures>,
}

impl PlanSummary {
    /// The figures of `path`, planned from `motion` for `robot`, with its
    /// angles in `units` (the motion's, or the robot's).
    pub fn new(motion: &Motion, robot: &Robot, path: &Trajectory, units: Units) -> Self {
        let rate = motion.rate_hz(robot);
        let moving = moving_times(path, rate);
        let joints = motion
            .joints
            .iter()
            .enumerate()
            .map(|(j, name)| {
                let s = path.joint_summary(j);
                let f = |get: fn(&servobus_trajectory::JointSummary) -> f64| {
                    s.as_ref().map_or(0.0, |s| units.from_rad(get(s)))
                };
                let jerk = f(|s| s.peak_jerk);
                JointPeaks {
                    name: name.clone(),
                    peak_velocity: f(|s| s.peak_velocity),
                    peak_acceleration: f(|s| s.peak_acceleration),
                    peak_jerk: jerk.is_finite().then_some(jerk),
                    min_position: tidy(f(|s| s.min_position)),
                    max_position: tidy(f(|s| s.max_position)),
                    moving_s: moving.get(j).copied().unwrap_or(0.0),
                }
            })
            .collect();
        let segments = path
            .segments()
            .iter()
            .map(|s| Segment {
                keyframe: s.keyframe,
                repetition: s.cycle,
                start_s: s.start,
                end_s: s.end,
            })
            .collect();
        PlanSummary {
            motion: motion.path.display().to_string(),
            robot: motion.robot_path.display().to_string(),
            units: units.to_string(),
            rate_hz: rate,
            interpolation: motion.path_shape(),
            duration_s: path.duration(),
            joints,
            segments,
            spatial: None,
        }
    }

    /// [`PlanSummary::new`] in the motion's units, with its figures in
    /// space (sampled at the control rate), and the spatial summary they
    /// came from (for a plot).
    pub fn of_motion(
        motion: &Motion,
        robot: &Robot,
        path: &Trajectory,
    ) -> (Self, Option<SpatialSummary>) {
        let spatial = spatial_summary(motion, robot, path, 1.0 / motion.rate_hz(robot));
        let mut summary = Self::new(motion, robot, path, motion.units);
        summary.spatial = spatial.as_ref().map(|s| SpaceFigures::new(s, motion.units));
        (summary, spatial)
    }
}

/// Rounding noise of the unit conversion (`-5e-16`) shown as the 0 it is.
fn tidy(x: f64) -> f64 {
    if x.abs() < 1e-9 {
        0.0
    } else {
        x
    }
}

/// Seconds each joint moves, sampled at the control rate (the rate the
/// scheduler will sample at): a cycle counts when the joint's speed is above
/// a thousandth of a degree per second.
fn moving_times(path: &Trajectory, rate_hz: f64) -> Vec<f64> {
    let n = path.joints();
    let mut out = vec![JointState::default(); n];
    let mut moving = vec![0.0; n];
    let dt = 1.0 / rate_hz;
    let mut cursor = path.cursor();
    let cycles = (path.duration() * rate_hz).ceil() as u64;
    let threshold = 1e-3f64.to_radians();
    for k in 0..cycles {
        path.sample_with(&mut cursor, k as f64 * dt, &mut out);
        for (m, s) in moving.iter_mut().zip(&out) {
            if s.velocity.abs() > threshold {
                *m += dt;
            }
        }
    }
    moving
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_summary_has_every_joint_and_segment_of_its_path_in_its_units() {
        let robot = crate::Robot::open("so101").expect("built-in robot");
        let motion = robot.motion("arm-wave").expect("built-in motion");
        let path = robot.plan(&motion).expect("plans");
        let degrees = PlanSummary::new(&motion, robot.config(), &path, Units::Deg);
        let radians = PlanSummary::new(&motion, robot.config(), &path, Units::Rad);
        assert_eq!(degrees.joints.len(), motion.joints.len());
        assert_eq!(degrees.segments.len(), path.segments().len());
        assert!((degrees.duration_s - path.duration()).abs() < 1e-12);
        for (d, r) in degrees.joints.iter().zip(&radians.joints) {
            assert!(
                (d.peak_velocity - r.peak_velocity.to_degrees()).abs() < 1e-9,
                "{d:?} {r:?}"
            );
            assert!(d.min_position <= d.max_position, "{d:?}");
            assert!(d.moving_s <= degrees.duration_s + 1e-9, "{d:?}");
        }
        let json = serde_json::to_value(&degrees).expect("serialises");
        assert_eq!(json["units"], "deg");
        assert!(json.get("spatial").is_none(), "no space figures asked for");
    }
}
