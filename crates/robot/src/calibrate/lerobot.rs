//! LeRobot calibration files, in and out.
//!
//! LeRobot keeps one JSON file per robot, one object per motor:
//! `{"id", "drive_mode", "homing_offset", "range_min", "range_max"}`. Its
//! ticks are present positions with `homing_offset` in the servo's register
//! 31, and its ranges never cross the seam (it centres them with that
//! offset). The file has no calibration pose: a LeRobot position is read
//! against the middle of the range, so an imported joint's calibration
//! pose is angle 0 at tick `(range_min + range_max) / 2`:
//!
//! - servobus angle = `direction x (tick - mid) x 360 / 4096`, with
//!   `direction` -1 when `drive_mode` is 1;
//! - LeRobot `DEGREES` = `(tick - mid) x 360 / 4095`, whatever the drive
//!   mode: the same for `drive_mode` 0, within 1/4096 of the angle (0.044
//!   deg at 180 deg; LeRobot divides by the largest tick, not the ticks per
//!   turn);
//! - LeRobot `RANGE_M100_100` = the tick clamped to the range, then
//!   `(tick - min) / (max - min) x 200 - 100`, negated with `drive_mode`;
//!   [`lerobot_value`] gives it from a servobus angle.

use std::fmt::Write as _;

use serde::Deserialize;

use crate::config::{Calibration, JointCalibration, Robot};

/// One motor of a LeRobot calibration file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LeRobotMotor {
    /// Servo ID.
    pub id: u8,
    /// 1 when the motor turns the other way.
    pub drive_mode: u8,
    /// Register 31.
    pub homing_offset: i32,
    /// Lowest present position.
    pub range_min: i64,
    /// Highest present position.
    pub range_max: i64,
}

/// LeRobot's normalisations of a position.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NormMode {
    /// Degrees from the middle of the range.
    Degrees,
    /// -100 at `range_min`, +100 at `range_max` (swapped by `drive_mode`).
    RangeM100To100,
    /// 0 at `range_min`, 100 at `range_max` (swapped by `drive_mode`).
    Range0To100,
}

/// Why a LeRobot file was refused.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LeRobotError {
    /// Not the JSON of a LeRobot calibration.
    #[error("not a LeRobot calibration file: {0}")]
    Json(#[from] serde_json::Error),
    /// A joint of the robot is not in the file.
    #[error(
        "no motor `{0}` in the LeRobot file (its motors are named as the robot file's joints)"
    )]
    MissingJoint(String),
    /// A motor has another ID than the robot file's joint.
    #[error("motor `{joint}` has ID {file} in the LeRobot file, {robot} in the robot file")]
    Id {
        /// The joint.
        joint: String,
        /// ID in the LeRobot file.
        file: u8,
        /// ID in the robot file.
        robot: u8,
    },
    /// A motor's values cannot be a calibration.
    #[error("motor `{0}`: drive_mode must be 0 or 1, range_min below range_max, both in 0..4095, |homing_offset| <= 2047")]
    Values(String),
}

/// The calibration of `robot` a LeRobot file describes.
///
/// # Errors
/// [`LeRobotError`] for bad JSON, a joint missing, another ID, or values
/// no servo can hold.
pub fn from_lerobot(robot: &Robot, json: &str, taken: &str) -> Result<Calibration, LeRobotError> {
    let motors: std::collections::HashMap<String, LeRobotMotor> = serde_json::from_str(json)?;
    let mut joints = Vec::with_capacity(robot.joint_count());
    for joint in robot.joints() {
        let m = motors
            .get(&joint.name)
            .ok_or_else(|| LeRobotError::MissingJoint(joint.name.clone()))?;
        if m.id != joint.id {
            return Err(LeRobotError::Id {
                joint: joint.name.clone(),
                file: m.id,
                robot: joint.id,
            });
        }
        let top = i64::from(joint.model.max_position());
        let ok = m.drive_mode <= 1
            && 0 <= m.range_min
            && m.range_min < m.range_max
            && m.range_max <= top
            && m.homing_offset.abs() <= crate::config::seam::MAX_HOMING_OFFSET;
        if !ok {
            return Err(LeRobotError::Values(joint.name.clone()));
        }
        joints.push(JointCalibration {
            name: joint.name.clone(),
            id: m.id,
            model: joint.model.name.to_owned(),
            firmware: None,
            homing_offset: m.homing_offset,
            pose_deg: 0.0,
            pose_tick: 0.5 * (m.range_min + m.range_max) as f64,
            direction: if m.drive_mode == 1 { -1 } else { 1 },
            range: [m.range_min, m.range_max],
        });
    }
    Ok(Calibration {
        robot: robot.name.clone(),
        taken: taken.to_owned(),
        joints,
    })
}

/// The LeRobot file of `cal`, in its joint order, laid out as LeRobot
/// writes it (4-space indent, no final newline). Each joint is given in the
/// frame it is played in, so that no range crosses the seam.
pub fn to_lerobot(cal: &Calibration) -> String {
    let mut out = String::from("{");
    for (i, j) in cal.joints.iter().enumerate() {
        let c = j.in_frame(j.play_frame());
        let sep = if i == 0 { "" } else { "," };
        let _ = write!(
            out,
            "{sep}\n    \"{}\": {{\n        \"id\": {},\n        \"drive_mode\": {},\n        \
             \"homing_offset\": {},\n        \"range_min\": {},\n        \"range_max\": {}\n    }}",
            json_escape(&c.name),
            c.id,
            u8::from(c.direction < 0),
            c.homing_offset,
            c.range[0],
            c.range[1]
        );
    }
    out.push_str("\n}");
    out
}

fn json_escape(s: &str) -> String {
    serde_json::to_string(s)
        .map(|q| q.trim_matches('"').to_owned())
        .unwrap_or_default()
}

/// LeRobot's value in `mode` for a joint at `deg` (servobus degrees) under
/// `cal`: what a LeRobot user's code reads for the same pose.
pub fn lerobot_value(cal: &JointCalibration, deg: f64, mode: NormMode) -> Option<f64> {
    let model = cal.servo_model()?;
    let c = cal.in_frame(cal.play_frame());
    let tick = c.pose_tick + f64::from(c.direction) * (deg - c.pose_deg) / model.deg_per_tick();
    let (min, max) = (c.range[0] as f64, c.range[1] as f64);
    let reversed = c.direction < 0;
    let clamped = tick.clamp(min, max);
    Some(match mode {
        NormMode::Degrees => (tick - 0.5 * (min + max)) * 360.0 / f64::from(model.max_position()),
        NormMode::RangeM100To100 => {
            let v = (clamped - min) / (max - min) * 200.0 - 100.0;
            if reversed {
                -v
            } else {
                v
            }
        }
        NormMode::Range0To100 => {
            let v = (clamped - min) / (max - min) * 100.0;
            if reversed {
                100.0 - v
            } else {
                v
            }
        }
    })
}
