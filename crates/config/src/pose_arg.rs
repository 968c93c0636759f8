//! A pose given on the command line (`fk --pose '{joint: angle, ...}'`):
//! joint names of the robot, each once, each a finite angle within the
//! joint's limits, in the robot file's units.

use serde::Deserialize;

use super::limits::Rounded;
use super::motion_poses::PoseMap;
use super::robot::Robot;
use super::Units;

/// Why a pose given as text is refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PoseError {
    /// Not a YAML map of names to numbers (or a name given twice).
    #[error("must be a map of joint names to angles, like `{{shoulder_pan: 30}}`: {0}")]
    Syntax(String),
    /// A name that is no joint of the robot.
    #[error("robot `{robot}` has no joint `{joint}` (joints: {known})")]
    UnknownJoint {
        /// The robot's name.
        robot: String,
        /// The name given.
        joint: String,
        /// The robot's joints, comma-separated.
        known: String,
    },
    /// An angle that is not a finite number.
    #[error("`{joint}` must be a finite angle, got {angle}")]
    NotFinite {
        /// The joint.
        joint: String,
        /// The value given.
        angle: f64,
    },
    /// An angle beyond the joint's limits.
    #[error(
        "`{joint}`: {} {units} is outside its limits [{}, {}] {units}",
        Rounded(*angle),
        Rounded(*min),
        Rounded(*max)
    )]
    OutsideLimits {
        /// The joint.
        joint: String,
        /// The angle given, in `units`.
        angle: f64,
        /// The joint's lowest angle, in `units`.
        min: f64,
        /// The joint's highest angle, in `units`.
        max: f64,
        /// The robot file's units.
        units: Units,
    },
}

/// `text`, a YAML map of joint names to angles in the robot file's units,
/// as every joint's angle in radians (robot order; joints not named at 0).
///
/// # Errors
/// [`PoseError`]: not a map (a name given twice is refused there too), a
/// name that is no joint, an angle that is not finite or beyond the
/// joint's limits.
pub fn parse_pose(robot: &Robot, text: &str) -> Result<Vec<f64>, PoseError> {
    let named = PoseMap::deserialize(serde_yaml::Deserializer::from_str(text))
        .map_err(|e| PoseError::Syntax(e.to_string()))?;
    let mut q = vec![0.0; robot.joint_count()];
    for (name, angle) in named.0 {
        let (Some(i), Some(joint)) = (robot.joint_index(&name), robot.joint(&name)) else {
            let known: Vec<&str> = robot.joints().map(|j| j.name.as_str()).collect();
            return Err(PoseError::UnknownJoint {
                robot: robot.name.clone(),
                joint: name,
                known: known.join(", "),
            });
        };
        if !angle.is_finite() {
            return Err(PoseError::NotFinite { joint: name, angle });
        }
        if !(joint.min..=joint.max).contains(&angle) {
            return Err(PoseError::OutsideLimits {
                joint: name,
                angle,
                min: joint.min,
                max: joint.max,
                units: robot.units,
            });
        }
        q[i] = robot.units.to_rad(angle);
    }
    Ok(q)
}
