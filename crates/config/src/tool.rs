//! Tool keyframes of a motion file (`tool: {xyz, pitch, roll}`), turned
//! into joint positions by inverse kinematics when the motion loads.

use serde::Deserialize;
use servobus_kinematics::{ArmIk, ArmTarget, IkError, Point3};

use super::robot::Robot;
use super::Units;

/// The name of an arm's tool frame in a robot file's geometry.
pub const TOOL_FRAME: &str = "tool";

/// A keyframe's `tool:`: where the robot's `tool` frame goes (mm, base
/// frame) and, optionally, its pitch and roll (the motion's angle unit).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ToolPose {
    pub(crate) xyz: [f64; 3],
    #[serde(default)]
    pub(crate) pitch: Option<f64>,
    #[serde(default)]
    pub(crate) roll: Option<f64>,
}

/// Why inverse kinematics found no angles, in `units`: the distance short,
/// the joint and its limits, or the singularity.
pub fn ik_reason(e: &IkError, units: Units) -> String {
    match e {
        IkError::JointLimit {
            joint,
            angle,
            min,
            max,
        } => format!(
            "joint `{joint}` would have to go to {:.1} {units}, outside its limits [{:.1}, {:.1}]",
            units.from_rad(*angle),
            units.from_rad(*min),
            units.from_rad(*max)
        ),
        other => other.to_string(),
    }
}

/// Puts the joints of the arm chain in `current` (the motion's `units`,
/// robot order; the previous keyframe's pose, which the answer stays
/// near) where they place the tool at `tool`; other joints are left as
/// they are.
///
/// # Errors
/// The reason as text: no geometry, no `tool` frame, a number that is not
/// finite, or why inverse kinematics found no angles ([`ik_reason`]).
pub(crate) fn resolve(
    robot: &Robot,
    units: Units,
    tool: &ToolPose,
    current: &mut [f64],
) -> Result<(), String> {
    let model = robot
        .geometry()
        .ok_or_else(|| format!("robot `{}` has no `kinematics:` section", robot.name))?;
    let arm = ArmIk::new(&model, TOOL_FRAME).map_err(|e| e.to_string())?;
    let numbers = tool.xyz.iter().chain(&tool.pitch).chain(&tool.roll);
    if !numbers.into_iter().all(|v| v.is_finite()) {
        return Err("xyz, pitch and roll must be finite numbers".to_owned());
    }
    let target = ArmTarget {
        xyz: Point3::from(tool.xyz),
        pitch: tool.pitch.map(|a| units.to_rad(a)),
        roll: tool.roll.map(|a| units.to_rad(a)),
    };
    let previous: Vec<f64> = arm
        .joints()
        .iter()
        .map(|&j| current.get(j).map_or(0.0, |&v| units.to_rad(v)))
        .collect();
    let mut out = vec![0.0; previous.len()];
    arm.solve(&target, &previous, &mut out)
        .map_err(|e| ik_reason(&e, units))?;
    for (&j, q) in arm.joints().iter().zip(out) {
        if let Some(c) = current.get_mut(j) {
            *c = units.from_rad(q);
        }
    }
    Ok(())
}
