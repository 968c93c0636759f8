//! Per-joint limits.

use crate::PlanError;

/// The limits of one joint, in the caller's units (for example rad, rad/s,
/// rad/s^2, rad/s^3; time is in seconds).
///
/// Velocity, acceleration and jerk limits are symmetric (the same bound in
/// both directions). Without a jerk limit the planner makes trapezoidal
/// velocity profiles (acceleration may jump); with one, 7-phase double-S.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointLimits {
    /// Lowest allowed position.
    pub min_position: f64,
    /// Highest allowed position.
    pub max_position: f64,
    /// Largest speed, > 0.
    pub max_velocity: f64,
    /// Largest acceleration magnitude, > 0.
    pub max_acceleration: f64,
    /// Largest jerk magnitude, > 0; `None` for no jerk limit.
    pub max_jerk: Option<f64>,
}

impl JointLimits {
    /// Limits with no position bounds (`-inf..inf`) and the given
    /// velocity, acceleration and jerk bounds.
    pub fn new(max_velocity: f64, max_acceleration: f64, max_jerk: Option<f64>) -> Self {
        JointLimits {
            min_position: f64::NEG_INFINITY,
            max_position: f64::INFINITY,
            max_velocity,
            max_acceleration,
            max_jerk,
        }
    }

    /// The same limits with position bounds `[min, max]`.
    pub fn with_positions(mut self, min: f64, max: f64) -> Self {
        self.min_position = min;
        self.max_position = max;
        self
    }

    /// Jerk bound, infinite when there is none. The profile formulas are
    /// written so that an infinite jerk gives the trapezoidal profile
    /// (every jerk phase has zero duration).
    #[inline]
    pub(crate) fn jerk(&self) -> f64 {
        self.max_jerk.unwrap_or(f64::INFINITY)
    }

    pub(crate) fn validate(&self, joint: usize) -> Result<(), PlanError> {
        let bad = |reason| Err(PlanError::InvalidLimits { joint, reason });
        if self.min_position.is_nan() || self.max_position.is_nan() {
            return bad("position limit is NaN");
        }
        if self.min_position > self.max_position {
            return bad("min_position > max_position");
        }
        if !(self.max_velocity.is_finite() && self.max_velocity > 0.0) {
            return bad("max_velocity must be finite and > 0");
        }
        if !(self.max_acceleration.is_finite() && self.max_acceleration > 0.0) {
            return bad("max_acceleration must be finite and > 0");
        }
        if let Some(j) = self.max_jerk {
            if !(j.is_finite() && j > 0.0) {
                return bad("max_jerk must be finite and > 0");
            }
        }
        Ok(())
    }
}

pub(crate) fn validate_all(limits: &[JointLimits]) -> Result<(), PlanError> {
    if limits.is_empty() {
        return Err(PlanError::NoJoints);
    }
    limits
        .iter()
        .enumerate()
        .try_for_each(|(j, l)| l.validate(j))
}

/// Checks keyframe `keyframe`'s positions, one per joint: finite and within
/// each joint's position limits.
pub(crate) fn check_keyframe(
    keyframe: usize,
    positions: &[f64],
    limits: &[JointLimits],
) -> Result<(), PlanError> {
    for (joint, (&p, l)) in positions.iter().zip(limits).enumerate() {
        if !p.is_finite() {
            return Err(PlanError::NotFinite { keyframe, joint });
        }
        if p < l.min_position || p > l.max_position {
            return Err(PlanError::OutOfRange {
                keyframe,
                joint,
                position: p,
                min: l.min_position,
                max: l.max_position,
            });
        }
    }
    Ok(())
}
