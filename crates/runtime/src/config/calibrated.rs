//! Applying a calibration file to a robot: each joint maps through its
//! calibration, and its limits shrink to what the joint was measured to reach.

use std::path::Path;

use super::calibration::{load_source, Calibration};
use super::error::{ConfigError, Source};
use super::locate::FieldPath;
use super::robot::{Robot, RobotCalibration};

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
