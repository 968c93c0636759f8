//! Dead reckoning: the base's pose on the floor from its body velocity.

use std::f64::consts::{PI, TAU};

use super::{BaseError, Twist};

/// Below this turn in one step (rad), the arc's factors `sin(p)/p` and
/// `(1 - cos(p))/p` are taken from their series: the closed forms divide
/// by nearly zero there. The first terms left out, `p^4 / 120` and
/// `p^5 / 720`, are below 1e-18 of the step: under f64's resolution.
const SERIES_BELOW_RAD: f64 = 1e-4;

/// The base's pose in the world (the floor where odometry started): x and
/// y in metres, heading in radians, counter-clockwise, in (-pi, pi].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Odometry {
    /// Position along the world's x, m.
    pub x_m: f64,
    /// Position along the world's y, m.
    pub y_m: f64,
    /// Heading from the world's x, counter-clockwise, rad in (-pi, pi].
    pub theta_rad: f64,
}

impl Odometry {
    /// Advances the pose by a body-frame velocity held for `dt` seconds.
    ///
    /// Exact for a constant twist: the base moves along the arc (or the
    /// straight line, when it does not turn) that the twist describes, so
    /// one step of `dt` and ten steps of `dt / 10` end at the same pose.
    ///
    /// # Errors
    ///
    /// [`BaseError::TwistNotFinite`] for a non-finite twist and
    /// [`BaseError::BadStep`] for a negative or non-finite `dt`; the pose
    /// is then left as it was.
    pub fn integrate(&mut self, body: &Twist, dt: f64) -> Result<(), BaseError> {
        body.check_finite()?;
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(BaseError::BadStep { dt });
        }
        let turn = body.theta * dt;
        // The displacement in the body frame at the start of the step is
        // `[[s, -c], [c, s]] * [x, y]`, where s and c integrate the heading's
        // cosine and sine over the step.
        let (s, c) = if turn.abs() < SERIES_BELOW_RAD {
            let t2 = turn * turn;
            (dt * (1.0 - t2 / 6.0), dt * turn / 2.0 * (1.0 - t2 / 12.0))
        } else {
            let half = (turn / 2.0).sin();
            // `1 - cos` as `2 sin^2` keeps its digits for small turns.
            (dt * turn.sin() / turn, dt * 2.0 * half * half / turn)
        };
        let dx = s * body.x - c * body.y;
        let dy = c * body.x + s * body.y;
        let (sin_h, cos_h) = self.theta_rad.sin_cos();
        self.x_m += cos_h * dx - sin_h * dy;
        self.y_m += sin_h * dx + cos_h * dy;
        self.theta_rad = wrap_angle(self.theta_rad + turn);
        Ok(())
    }
}

/// An angle brought into (-pi, pi].
pub(crate) fn wrap_angle(a: f64) -> f64 {
    // `rem_euclid` lands in [0, 2pi], 2pi itself only by rounding.
    let r = a.rem_euclid(TAU);
    if r > PI {
        r - TAU
    } else {
        r
    }
}
