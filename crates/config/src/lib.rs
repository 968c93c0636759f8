//! Robot, motion and calibration files: loading, validation, the built-in
//! files, and the mapping between joint angles and servo ticks.
//!
//! This crate knows the files and what they mean; it runs nothing. The
//! scheduler (`servobus-runtime`) and the programs that drive a robot build
//! on it, and so do the simulator's body files, which report their errors
//! the same way ([`Source`], [`FieldPath`]).
//!
//! A robot file describes buses, servos and joint limits; a motion file
//! describes poses and keyframes for one robot. Both are validated in full
//! before anything moves, and every problem is reported as
//! `file:line:column: field: reason`:
//!
//! ```text
//! configs/robots/so101.yaml:14:13: buses[0].joints[1].id: ID 1 is already used on bus `arm` by joint 0
//! configs/motions/arm-wave.yaml:21:24: keyframes[2].pose.elbow_flex: keyframe 2: 120 deg is outside the limits of joint `elbow_flex` [-100, 95] deg
//! ```
//!
//! ```no_run
//! use std::path::Path;
//! use servobus_config::{load_motion, JointMap};
//!
//! let (motion, robot) = load_motion(Path::new("configs/motions/arm-wave.yaml"), None)?;
//! let joint = robot.joint("elbow_flex").expect("the arm has an elbow");
//! let map = JointMap::new(joint, robot.units);
//! let goal = map.goal(motion.units.to_rad(45.0));
//! println!("{} keyframes; elbow at 45 deg = tick {}", motion.keyframes.len(), goal.value);
//! # Ok::<(), servobus_config::ConfigError>(())
//! ```

mod budget;
pub mod builtin;
mod calibrated;
mod calibration;
mod error;
mod files;
pub mod limits;
mod locate;
mod mapping;
mod motion;
mod motion_keyframes;
mod motion_poses;
mod nesting;
mod plan_terms;
mod pose_arg;
mod robot;
pub mod seam;
mod spatial;
mod syntax;
mod terms;
mod tool;
mod trajectory;
mod units;

pub use budget::RateError;
pub use calibrated::{limit_origins, LimitOrigin};
pub use calibration::{
    load_calibration, save_calibration, utc_now, Calibration, CalibrationSaveError,
    JointCalibration, PlayFrame, RANGE_MARGIN_DEG,
};
pub use error::ConfigError;
pub use files::{builtin_path, is_builtin_path, BuiltinFile, BUILTIN_DIR};
// For the simulator's body files, which report errors the same way.
pub use error::Source;
pub use locate::FieldPath;
pub use mapping::{Clamped, JointMap};
pub use motion::{
    load_motion, load_motion_calibrated, load_motion_text, Interpolation, Keyframe, KeyframeGrasp,
    Motion, OnLimit,
};
pub use pose_arg::{parse_pose, PoseError};
pub use robot::{
    load_robot, BaseTarget, BaseTargetError, BusConfig, CalibrationChoice, FaultResponse,
    JointConfig, JointFaults, JointMode, Robot, RobotCalibration, RobotOptions, RobotSource,
    ServoSettings, ServoWrite, WheelTargets, MODEL_JERK_RAMP_S,
};
pub use spatial::{spatial_summary, FeetSummary, SpatialSummary, ToolSummary};
pub use tool::{ik_reason, TOOL_FRAME};
pub use trajectory::{check_motion_length, joint_limits, plan_input, plan_motion};
pub use units::Units;
