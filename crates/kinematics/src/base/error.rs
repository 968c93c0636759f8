//! The typed errors of checking a `base:` section and of driving a base.

use thiserror::Error;

/// A problem with a base's geometry or with what it was asked to do.
/// Geometry errors name the field in the robot file (`base.omni3.wheels[1].joint`);
/// velocity errors name the field of the `base` target (`base.y`).
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum BaseError {
    /// A length that is zero, negative or not a number.
    #[error("{field}: must be a finite number > 0, not {value}")]
    NotPositive {
        /// The field, e.g. `base.omni3.wheel_radius_mm`.
        field: String,
        /// The value given.
        value: f64,
    },
    /// An angle that is infinite or not a number.
    #[error("{field}: must be a finite number, not {value}")]
    NotFinite {
        /// The field, e.g. `base.omni3.wheels[0].angle_deg`.
        field: String,
        /// The value given.
        value: f64,
    },
    /// A wheel driven by a joint the robot does not have.
    #[error("{field}: no joint called {joint:?}")]
    UnknownJoint {
        /// The field, e.g. `base.differential.left`.
        field: String,
        /// The name given.
        joint: String,
    },
    /// Two wheels driven by one joint.
    #[error("{field}: joint {joint:?} already drives {other} (each wheel needs its own joint)")]
    SharedJoint {
        /// The field of the second wheel.
        field: String,
        /// The joint.
        joint: String,
        /// The field of the first wheel that names it.
        other: String,
    },
    /// An omni3 base with other than three wheels.
    #[error("base.omni3.wheels: an omni3 base has exactly 3 wheels, not {count}")]
    WheelCount {
        /// How many were given.
        count: usize,
    },
    /// Two omni wheels at (nearly) the same place around the centre: the
    /// base could not be driven in every direction.
    #[error(
        "base.omni3.wheels: wheels[{first}] ({first_deg} deg) and wheels[{second}] ({second_deg} deg) \
         are less than {MIN_SEPARATION_DEG} deg apart; the three wheels must sit at three different \
         angles around the centre (e.g. 30, 150, 270)"
    )]
    CloseWheels {
        /// The index of one wheel.
        first: usize,
        /// Its `angle_deg`.
        first_deg: f64,
        /// The index of the other.
        second: usize,
        /// Its `angle_deg`.
        second_deg: f64,
    },
    /// All three omni wheels at the same place around the centre.
    #[error(
        "base.omni3.wheels: all three wheels sit at {angle_deg} deg around the centre; they must sit \
         at three different angles (e.g. 30, 150, 270)"
    )]
    SameAngle {
        /// The angle of the first wheel.
        angle_deg: f64,
    },
    /// An omni3 geometry whose wheel map has no usable inverse (radii far
    /// outside what a robot has).
    #[error(
        "base.omni3: wheel_radius_mm and base_radius_mm give wheel speeds that cannot be inverted \
         (use the robot's radii in mm)"
    )]
    Singular,
    /// A differential base asked to move sideways.
    #[error("base.y: a differential base cannot move sideways (y = {y} m/s; use x and theta)")]
    Sideways {
        /// The sideways speed asked for, m/s.
        y: f64,
    },
    /// A base velocity so large that a wheel speed is not a finite number.
    #[error(
        "base: the wheel speeds for this velocity are not finite numbers (x and y are m/s, theta rad/s)"
    )]
    Overflow,
    /// A base velocity that is infinite or not a number.
    #[error("base.{field}: must be a finite number, not {value}")]
    TwistNotFinite {
        /// `x`, `y` or `theta`.
        field: &'static str,
        /// The value given.
        value: f64,
    },
    /// A slice of per-wheel values of the wrong length.
    #[error("{what}: {expected} values expected (one per wheel), not {actual}")]
    WheelSlice {
        /// Which slice: `wheel speeds`, `wheel limits`, `output`.
        what: &'static str,
        /// The base's number of wheels.
        expected: usize,
        /// The slice's length.
        actual: usize,
    },
    /// A wheel speed limit that is zero, negative or not a number.
    #[error(
        "speed limit of wheel joint {joint:?}: must be a finite number > 0 rad/s, not {value}"
    )]
    BadLimit {
        /// The wheel's joint.
        joint: String,
        /// The limit given.
        value: f64,
    },
    /// A measured wheel speed that is infinite or not a number.
    #[error("measured speed of wheel joint {joint:?}: must be a finite number, not {value}")]
    BadMeasurement {
        /// The wheel's joint.
        joint: String,
        /// The speed given.
        value: f64,
    },
    /// An odometry step that is negative or not a number.
    #[error("odometry step: dt must be a finite number >= 0 s, not {dt}")]
    BadStep {
        /// The step given, s.
        dt: f64,
    },
}

/// Omni wheels closer than this around the centre are refused: the wheel
/// map is singular when two coincide, and ill-conditioned (huge wheel
/// speeds for small motions) just beside that.
pub const MIN_SEPARATION_DEG: f64 = 1.0;
