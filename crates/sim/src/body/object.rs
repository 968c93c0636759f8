//! An object in a joint's way: what a gripper closes on.
//!
//! The object's surface is at a physical angle of the joint and the object
//! fills the side of it away from where the joint starts. It is soft: the
//! deeper the shaft squeezes into it, the harder it pushes back,
//! `stiffness` percent of the servo's full torque per degree of squeeze:
//!
//! ```text
//!   joint starts here        surface (at)       object
//!   ----------o----------------->|//////////////////////
//!                                |<- squeeze ->|
//!                     push back = stiffness/100 * squeeze  (fraction of full torque)
//! ```
//!
//! With torque on the object's push is a load on the motor
//! ([`Body::hand_load`](super::Body)), so the shaft settles where the two
//! balance: driven towards a goal well inside the object the motor
//! saturates at its torque limit and the squeeze is `torque_limit * 100 /
//! stiffness` degrees; the present load and current read the limit and the
//! servo is stalled, as against a stop. The object gives way at most
//! [`GIVE_SPEED_DEG_S`] (a soft object compresses; the motor cannot slam the
//! shaft into it in one step), and pushes the shaft out as fast as the
//! servo's own load model lets it when the motor yields (a lower torque
//! limit, a goal back out). With torque off the object is a stop at its
//! surface: a hand turning the joint cannot push through it.

/// The stiffness of an object whose hand file does not say, in percent of
/// full torque per degree of squeeze: a firm rubber ball in a small
/// gripper, squeezed 5 degrees at full torque.
pub const DEFAULT_STIFFNESS: f64 = 20.0;

/// The stiffest object the simulation resolves, in percent of full torque
/// per degree: full torque squeezes it 0.1 degree, about one sensor tick of
/// an STS3215 (stiffer ones would make the load model's step overshoot).
pub const MAX_STIFFNESS: f64 = 1000.0;

/// The fastest an object gives way under a shaft squeezing into it, deg/s.
pub const GIVE_SPEED_DEG_S: f64 = 30.0;

/// A joint angle this close to the surface counts as on it, degrees.
const ON_SURFACE_DEG: f64 = 1e-6;

/// An object a hand puts in a joint's way (see the [module](self) docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandObject {
    at_deg: f64,
    stiffness: f64,
}

impl HandObject {
    /// An object whose surface is at physical angle `at_deg` of the joint,
    /// `stiffness` percent of full torque per degree of squeeze; `None`
    /// unless `at_deg` is finite and `stiffness` is in `(0,`
    /// [`MAX_STIFFNESS`]`]`.
    ///
    /// ```
    /// use servobus_sim::body::HandObject;
    /// let ball = HandObject::new(25.0, 20.0).unwrap();
    /// assert_eq!(ball.squeeze_deg(1.0), 5.0);
    /// assert!(HandObject::new(25.0, -1.0).is_none());
    /// ```
    pub fn new(at_deg: f64, stiffness: f64) -> Option<HandObject> {
        let ok = at_deg.is_finite() && stiffness > 0.0 && stiffness <= MAX_STIFFNESS;
        ok.then_some(HandObject { at_deg, stiffness })
    }

    /// The surface's physical angle, degrees.
    pub fn at_deg(&self) -> f64 {
        self.at_deg
    }

    /// Percent of full torque per degree of squeeze.
    pub fn stiffness(&self) -> f64 {
        self.stiffness
    }

    /// How far, in degrees, the object is squeezed when it pushes back
    /// with `torque` (a fraction of full torque; its sign is ignored).
    pub fn squeeze_deg(&self, torque: f64) -> f64 {
        torque.abs() * 100.0 / self.stiffness
    }
}

/// An object as one body holds it: the side of the surface it fills,
/// decided from where the joint was when the body first met it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Contact {
    pub object: HandObject,
    /// +1: the object fills the angles above its surface; -1: below.
    side: f64,
}

impl Contact {
    /// The object as a joint at `angle_deg` meets it: it fills the side of
    /// the surface away from the joint, and the side above it when the joint
    /// is on the surface (the side cannot be told).
    pub(crate) fn new(object: HandObject, angle_deg: f64) -> Contact {
        let side = if angle_deg > object.at_deg + ON_SURFACE_DEG {
            -1.0
        } else {
            1.0
        };
        Contact { object, side }
    }

    /// How deep the joint at `angle_deg` is in the object, degrees
    /// (negative outside it).
    pub(crate) fn squeeze_deg(&self, angle_deg: f64) -> f64 {
        self.side * (angle_deg - self.object.at_deg)
    }

    /// The object's push on a joint at `angle_deg`, as a fraction of full
    /// torque, positive towards higher angles.
    pub(crate) fn push(&self, angle_deg: f64) -> f64 {
        let squeeze = self.squeeze_deg(angle_deg).max(0.0);
        -self.side * squeeze * self.object.stiffness / 100.0
    }

    /// The angle the object lets a joint take that moved from `before_deg`
    /// towards `angle_deg` in `dt` seconds: with torque on it gives way by at
    /// most [`GIVE_SPEED_DEG_S`] `* dt` beyond the squeeze it had; with
    /// torque off (nothing squeezes it) it holds the joint at its surface.
    pub(crate) fn admit(&self, angle_deg: f64, before_deg: f64, dt: f64, torque_on: bool) -> f64 {
        let squeeze = self.squeeze_deg(angle_deg);
        if squeeze <= 0.0 {
            return angle_deg;
        }
        let allowed = if torque_on {
            self.squeeze_deg(before_deg).max(0.0) + GIVE_SPEED_DEG_S * dt.max(0.0)
        } else {
            0.0
        };
        if squeeze <= allowed {
            angle_deg
        } else {
            self.object.at_deg + self.side * allowed
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ball() -> HandObject {
        HandObject::new(25.0, 20.0).expect("a valid object")
    }

    #[test]
    fn the_object_fills_the_side_away_from_the_start() {
        let below = Contact::new(ball(), 60.0);
        assert_eq!(below.squeeze_deg(20.0), 5.0);
        assert!(below.push(20.0) > 0.0, "pushes the joint back up");
        let above = Contact::new(ball(), 0.0);
        assert_eq!(above.squeeze_deg(30.0), 5.0);
        assert!(
            (above.push(30.0) + 1.0).abs() < 1e-12,
            "full torque at 5 deg"
        );
        assert_eq!(above.push(10.0), 0.0, "no push outside");
        // On the surface the side cannot be told: the object is above.
        assert_eq!(Contact::new(ball(), 25.0).squeeze_deg(26.0), 1.0);
    }

    #[test]
    fn the_object_gives_way_slowly_with_torque_on_and_not_at_all_with_it_off() {
        let c = Contact::new(ball(), 0.0);
        assert_eq!(c.admit(20.0, 10.0, 0.001, true), 20.0, "outside: free");
        let a = c.admit(40.0, 24.0, 0.001, true);
        assert!((a - (25.0 + GIVE_SPEED_DEG_S * 0.001)).abs() < 1e-12, "{a}");
        let a = c.admit(40.0, 27.0, 0.001, true);
        assert!((a - (27.0 + GIVE_SPEED_DEG_S * 0.001)).abs() < 1e-12, "{a}");
        assert_eq!(c.admit(26.0, 27.0, 0.001, true), 26.0, "backing out: free");
        assert_eq!(
            c.admit(40.0, 27.0, 0.001, false),
            25.0,
            "torque off: the surface"
        );
    }

    #[test]
    fn bad_objects_are_refused() {
        assert!(HandObject::new(f64::NAN, 20.0).is_none());
        assert!(HandObject::new(25.0, 0.0).is_none());
        assert!(HandObject::new(25.0, f64::INFINITY).is_none());
        assert!(HandObject::new(25.0, MAX_STIFFNESS * 2.0).is_none());
        assert!(HandObject::new(25.0, MAX_STIFFNESS).is_some());
    }
}
