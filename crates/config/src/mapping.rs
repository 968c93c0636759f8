//! Joint positions <-> servo ticks, and the last-step clamp to joint limits.

use super::seam::{turn_ticks, unwrap_near};
use super::{JointConfig, Units};

/// How one joint's angle maps to its servo's position register.
///
/// The servo's angle, measured from the middle of its range (tick
/// `resolution / 2`: 2048 on an STS3215, 512 on an SCS0009), is
/// `offset + position` (or `offset - position` when `inverted`). Ticks are
/// that angle times `resolution / range`, rounded to the nearest tick.
/// Everything here is in radians, the trajectory's unit; the robot's unit is
/// converted once, when the map is built.
///
/// A calibrated joint ([`JointConfig::calibration`]) maps instead through
/// its calibration, in its play frame
/// ([`JointCalibration::play_frame`](super::JointCalibration::play_frame)):
/// the tick of the calibration pose and the direction give the line, and a
/// reading is unwrapped to lie within half a turn of the measured range's
/// middle, so a joint just past the seam reads as just past its end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointMap {
    /// Lower joint limit, rad.
    pub min_rad: f64,
    /// Upper joint limit, rad.
    pub max_rad: f64,
    /// Tick at joint position 0.
    zero_tick: f64,
    /// Ticks per radian of joint motion, negative when inverted.
    ticks_per_rad: f64,
    /// Highest tick the servo accepts.
    max_tick: i32,
    /// Calibrated full-turn joints: the middle of the measured range and
    /// the ticks of a turn, to unwrap readings near it.
    unwrap: Option<(f64, i32)>,
}

/// A goal after the last-step clamp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clamped<T> {
    /// The value sent.
    pub value: T,
    /// Whether the requested value was outside the joint limits (or not a
    /// number). A clamp means the plan was wrong: the scheduler counts it.
    pub clamped: bool,
}

impl JointMap {
    /// The map of `joint`, whose angles are in `units`.
    pub fn new(joint: &JointConfig, units: Units) -> Self {
        let model = joint.model;
        if let Some(cal) = &joint.calibration {
            let c = cal.in_frame(cal.play_frame());
            let ticks_per_rad = 1.0 / model.deg_per_tick().to_radians();
            let sign = f64::from(c.direction.signum());
            let middle = 0.5 * (c.range[0] + c.range[1]) as f64;
            return JointMap {
                min_rad: units.to_rad(joint.min),
                max_rad: units.to_rad(joint.max),
                zero_tick: c.pose_tick - sign * c.pose_deg.to_radians() * ticks_per_rad,
                ticks_per_rad: sign * ticks_per_rad,
                max_tick: i32::try_from(model.max_position()).unwrap_or(i32::MAX),
                unwrap: turn_ticks(model).map(|turn| (middle, turn)),
            };
        }
        let ticks_per_rad = f64::from(model.resolution) / model.range_deg.to_radians();
        let sign = if joint.inverted { -1.0 } else { 1.0 };
        let mid = f64::from(model.resolution / 2);
        JointMap {
            min_rad: units.to_rad(joint.min),
            max_rad: units.to_rad(joint.max),
            zero_tick: mid + units.to_rad(joint.offset) * ticks_per_rad,
            ticks_per_rad: sign * ticks_per_rad,
            max_tick: i32::try_from(model.max_position()).unwrap_or(i32::MAX),
            unwrap: None,
        }
    }

    /// Unrounded, unclamped tick of a joint position.
    pub fn raw_ticks(&self, rad: f64) -> f64 {
        self.zero_tick + rad * self.ticks_per_rad
    }

    /// Joint positions (in `units`) at the two ends of the servo's range.
    pub(crate) fn servo_range(&self, units: Units) -> (f64, f64) {
        let a = units.from_rad(self.from_ticks(0));
        let b = units.from_rad(self.from_ticks(self.max_tick));
        (a.min(b), a.max(b))
    }

    /// Ticks of joint position `rad`, rounded and kept inside the servo's
    /// range (the joint limits are not applied: see [`JointMap::goal`]).
    /// Never wrapped: a goal past the end of the register would send the
    /// servo the long way round; a calibrated joint's limits keep its goals
    /// inside the measured range, which lies inside the register.
    pub fn to_ticks(&self, rad: f64) -> i32 {
        let t = self.raw_ticks(rad).round();
        if t.is_nan() {
            return self.max_tick / 2;
        }
        // The float-to-int cast saturates; the clamp keeps it in the register.
        (t as i32).clamp(0, self.max_tick)
    }

    /// Joint position, rad, of a position register reading.
    pub fn from_ticks(&self, ticks: i32) -> f64 {
        let t = match self.unwrap {
            Some((middle, turn)) => unwrap_near(f64::from(ticks), middle, turn),
            None => f64::from(ticks),
        };
        (t - self.zero_tick) / self.ticks_per_rad
    }

    /// Joint position `rad` clamped to the joint limits. Not-a-number goes
    /// to the middle of the limits, and counts as clamped.
    pub fn clamp(&self, rad: f64) -> Clamped<f64> {
        if rad.is_nan() {
            return Clamped {
                value: 0.5 * (self.min_rad + self.max_rad),
                clamped: true,
            };
        }
        let value = rad.clamp(self.min_rad, self.max_rad);
        Clamped {
            value,
            clamped: value != rad,
        }
    }

    /// The goal ticks for joint position `rad`: clamped to the joint limits
    /// (the last step before encoding), then converted.
    pub fn goal(&self, rad: f64) -> Clamped<i32> {
        let c = self.clamp(rad);
        Clamped {
            value: self.to_ticks(c.value),
            clamped: c.clamped,
        }
    }
}
