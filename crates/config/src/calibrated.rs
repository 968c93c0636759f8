//! Applying a calibration file to a robot: each joint maps through its
//! calibration, and its limits shrink to what the joint was measured to reach.

use std::path::Path;

use super::calibration::{load_source, Calibration};
use super::error::{ConfigError, Source};
use super::locate::FieldPath;
use super::robot::{JointConfig, Robot, RobotCalibration};
use super::Units;

/// Where one of a joint's limits comes from: a limit error names it, so
/// that the user knows which file to change (or whether to calibrate
/// again).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LimitOrigin {
    /// The robot file's `min` or `max`.
    RobotFile,
    /// The calibration: the range measured there, less its margin.
    Calibration,
}

impl std::fmt::Display for LimitOrigin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            LimitOrigin::RobotFile => "the robot file's `min`/`max`",
            LimitOrigin::Calibration => "the calibration (the measured range, less its margin)",
        })
    }
}

/// Where `joint`'s lower and upper limits (in `units`) come from: the
/// calibration where its measured range is what bounds the joint, the robot
/// file otherwise.
pub fn limit_origins(joint: &JointConfig, units: Units) -> [LimitOrigin; 2] {
    let Some(cal) = &joint.calibration else {
        return [LimitOrigin::RobotFile; 2];
    };
    let (lo_deg, hi_deg) = cal.limits_deg(joint.model);
    let from = |limit: f64, measured_deg: f64| {
        let measured = Units::Deg.convert(measured_deg, units);
        if (limit - measured).abs() <= 1e-9 * measured.abs().max(1.0) {
            LimitOrigin::Calibration
        } else {
            LimitOrigin::RobotFile
        }
    };
    [from(joint.min, lo_deg), from(joint.max, hi_deg)]
}

/// `robot` with the calibration file at `path` applied.
///
/// # Errors
/// The file's own errors ([`load_calibration`](super::load_calibration)),
/// and, pointing into it: another robot's name, a joint of the robot it
/// lacks, another servo ID or model than the robot file's, or a measured
/// range that leaves nothing of a joint's limits.
pub(crate) fn apply(mut robot: Robot, path: &Path) -> Result<Robot, ConfigError> {
    let (cal, src) = load_source(path)?;
    check_robot(&robot, &cal, &src)?;
    let units = robot.units;
    for bus in &mut robot.buses {
        for joint in &mut bus.joints {
            let Some((i, jc)) = cal
                .joints
                .iter()
                .enumerate()
                .find(|(_, c)| c.name == joint.name)
            else {
                return Err(src.error(
                    &FieldPath::root().key("joints"),
                    format!(
                        "no calibration of joint `{}`: calibrate the robot again",
                        joint.name
                    ),
                ));
            };
            let jp = FieldPath::root().key("joints").index(i);
            if jc.id != joint.id {
                return Err(src.error(
                    &jp.key("id"),
                    format!(
                        "taken with servo ID {} but the robot file gives `{}` ID {}",
                        jc.id, joint.name, joint.id
                    ),
                ));
            }
            if !jc.model.eq_ignore_ascii_case(joint.model.name) {
                return Err(src.error(
                    &jp.key("model"),
                    format!(
                        "taken on a {} but the robot file gives `{}` a {}",
                        jc.model, joint.name, joint.model.name
                    ),
                ));
            }
            if joint.is_wheel() {
                // A wheel turns without end: its measured range bounds
                // nothing.
                joint.calibration = Some(jc.clone());
                continue;
            }
            let (lo_deg, hi_deg) = jc.limits_deg(joint.model);
            let lo = joint.min.max(super::Units::Deg.convert(lo_deg, units));
            let hi = joint.max.min(super::Units::Deg.convert(hi_deg, units));
            // Also refuses NaN limits.
            if lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
                return Err(src.error(
                    &jp.key("range"),
                    format!(
                        "`{}` was measured to reach {lo_deg:.1}..{hi_deg:.1} deg (less the margin), \
                         which leaves nothing of its limits [{}, {}] {units}: was the calibration \
                         pose right?",
                        joint.name, joint.min, joint.max
                    ),
                ));
            }
            joint.min = lo;
            joint.max = hi;
            joint.home = joint.home.map(|h| h.clamp(lo, hi));
            joint.calibration = Some(jc.clone());
        }
    }
    robot.calibration = RobotCalibration::Applied {
        path: path.to_owned(),
    };
    Ok(robot)
}

fn check_robot(robot: &Robot, cal: &Calibration, src: &Source) -> Result<(), ConfigError> {
    if cal.robot != robot.name {
        return Err(src.error(
            &FieldPath::root().key("robot"),
            format!(
                "this calibration is of a `{}` robot, not `{}`",
                cal.robot, robot.name
            ),
        ));
    }
    Ok(())
}
