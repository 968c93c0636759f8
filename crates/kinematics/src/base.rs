//! Wheeled bases: wheel speeds from a base velocity, the base velocity
//! from measured wheel speeds, and odometry.
//!
//! A robot file's `base:` section ([`BaseSpec`]) describes the wheels; a
//! [`Base`] is that section checked against the robot's joints. The
//! runtime turns a velocity target into wheel speeds with
//! [`Base::wheel_speeds`] (or [`Base::limited`], which slows the whole base
//! down rather than bending its path when a wheel would be too fast), turns
//! the measured wheel speeds back into a [`Twist`] with [`Base::twist`] and
//! integrates that into a pose on the floor with [`Odometry::integrate`].
//!
//! ```text
//!             +x forward          omni angle_deg: 0 ahead, 90 left, 180 behind,
//!              ^                  270 right; theta > 0 turns counter-clockwise
//!              |                  seen from above (z up, out of the page)
//!   +y left <--+
//! ```
//!
//! | quantity | unit | convention |
//! |---|---|---|
//! | `Twist::x`, `Twist::y` | m/s | body frame: x forward, y left |
//! | `Twist::theta` | rad/s | counter-clockwise seen from above (about z up) |
//! | wheel speeds | rad/s | one per wheel, in the order of [`Base::wheels`] |
//! | omni `angle_deg` | degrees | where the wheel sits around the centre, from +x, counter-clockwise |
//! | omni wheel, positive | | rolls tangentially, counter-clockwise about the centre |
//! | differential wheel, positive | | rolls the base forward |
//! | `*_mm` in the file | mm | converted to metres here |
//! | [`Odometry`] | m, rad | world frame where odometry started; heading in (-pi, pi] |
//!
//! With `R` the base radius, `r` the wheel radius and `T` the track, an
//! omni wheel at angle `a` turns at `(-sin(a) x + cos(a) y + R theta) / r`;
//! a differential base's left wheel at `(x - theta T / 2) / r` and its right
//! wheel at `(x + theta T / 2) / r`. The omni map is inverted once, when
//! the base is checked; none of the per-cycle methods allocates.

mod error;
mod odometry;
mod spec;
#[cfg(test)]
mod tests;

use nalgebra::{Matrix3, Vector3};

pub use error::{BaseError, MIN_SEPARATION_DEG};
pub use odometry::Odometry;
pub use spec::{BaseSpec, DifferentialSpec, Omni3Spec, OmniWheelSpec};

/// A sideways speed a differential base ignores as rounding, m/s.
const SIDEWAYS_TOLERANCE_M_S: f64 = 1e-9;

/// A base velocity in the base's own frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Twist {
    /// Forward speed, m/s.
    pub x: f64,
    /// Speed to the left, m/s.
    pub y: f64,
    /// Turn rate, counter-clockwise seen from above, rad/s.
    pub theta: f64,
}

impl Twist {
    /// Refuses a twist with an infinite or NaN component, naming it.
    pub(crate) fn check_finite(&self) -> Result<(), BaseError> {
        for (field, value) in [("x", self.x), ("y", self.y), ("theta", self.theta)] {
            if !value.is_finite() {
                return Err(BaseError::TwistNotFinite { field, value });
            }
        }
        Ok(())
    }
}

/// Which kind of base a [`Base`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BaseKind {
    /// Three omni wheels: moves in x, y and theta.
    Omni3,
    /// Two wheels on one axle: moves in x and theta only.
    Differential,
}

/// A wheeled base checked against the robot's joints: the maps between
/// its velocity and its wheel speeds.
#[derive(Debug, Clone, PartialEq)]
pub struct Base {
    /// Joint index of each wheel, in the spec's order.
    wheels: Vec<usize>,
    /// Joint name of each wheel, for errors.
    names: Vec<String>,
    model: Model,
}

#[derive(Debug, Clone, PartialEq)]
enum Model {
    Omni3 {
        /// Twist `[x, y, theta]` to wheel speeds.
        to_wheels: Matrix3<f64>,
        /// Its inverse.
        to_twist: Matrix3<f64>,
    },
    Differential {
        radius_m: f64,
        track_m: f64,
    },
}

/// The wheels found so far while checking a spec.
#[derive(Default)]
struct Wheels {
    indices: Vec<usize>,
    names: Vec<String>,
    fields: Vec<String>,
}

impl Wheels {
    /// Looks up the joint named at `field`, refusing an unknown joint and
    /// one that already drives a wheel.
    fn add(
        &mut self,
        field: String,
        joint: &str,
        joint_index: &dyn Fn(&str) -> Option<usize>,
    ) -> Result<(), BaseError> {
        let Some(index) = joint_index(joint) else {
            return Err(BaseError::UnknownJoint {
                field,
                joint: joint.to_owned(),
            });
        };
        if let Some(i) = self.indices.iter().position(|&k| k == index) {
            return Err(BaseError::SharedJoint {
                field,
                joint: joint.to_owned(),
                other: self.fields[i].clone(),
            });
        }
        self.indices.push(index);
        self.names.push(joint.to_owned());
        self.fields.push(field);
        Ok(())
    }
}

/// A length in mm that must be positive, in metres.
fn positive_m(field: &str, value_mm: f64) -> Result<f64, BaseError> {
    if value_mm.is_finite() && value_mm > 0.0 {
        Ok(value_mm / 1000.0)
    } else {
        Err(BaseError::NotPositive {
            field: field.to_owned(),
            value: value_mm,
        })
    }
}

/// The angle between two directions given in degrees, in [0, 180].
fn apart_deg(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

/// Refuses omni wheels at (nearly) the same angle: the wheel map is
/// singular exactly when two of them coincide.
fn check_separation(angles_deg: [f64; 3]) -> Result<(), BaseError> {
    let close = |i: usize, j: usize| apart_deg(angles_deg[i], angles_deg[j]) < MIN_SEPARATION_DEG;
    let pairs = [(0, 1), (0, 2), (1, 2)];
    match pairs.iter().filter(|&&(i, j)| close(i, j)).count() {
        0 => Ok(()),
        1 => {
            let (first, second) = pairs
                .into_iter()
                .find(|&(i, j)| close(i, j))
                .unwrap_or((0, 1));
            Err(BaseError::CloseWheels {
                first,
                first_deg: angles_deg[first],
                second,
                second_deg: angles_deg[second],
            })
        }
        _ => Err(BaseError::SameAngle {
            angle_deg: angles_deg[0],
        }),
    }
}

fn omni3(spec: &Omni3Spec, joint_index: &dyn Fn(&str) -> Option<usize>) -> Result<Base, BaseError> {
    let r = positive_m("base.omni3.wheel_radius_mm", spec.wheel_radius_mm)?;
    let big_r = positive_m("base.omni3.base_radius_mm", spec.base_radius_mm)?;
    let [w0, w1, w2] = spec.wheels.as_slice() else {
        return Err(BaseError::WheelCount {
            count: spec.wheels.len(),
        });
    };
    let mut wheels = Wheels::default();
    for (i, wheel) in [w0, w1, w2].into_iter().enumerate() {
        if !wheel.angle_deg.is_finite() {
            return Err(BaseError::NotFinite {
                field: format!("base.omni3.wheels[{i}].angle_deg"),
                value: wheel.angle_deg,
            });
        }
        wheels.add(
            format!("base.omni3.wheels[{i}].joint"),
            &wheel.joint,
            joint_index,
        )?;
    }
    let angles_deg = [w0.angle_deg, w1.angle_deg, w2.angle_deg];
    check_separation(angles_deg)?;
    let mut to_wheels = Matrix3::zeros();
    for (i, a) in angles_deg.into_iter().enumerate() {
        let (sin, cos) = a.to_radians().sin_cos();
        to_wheels[(i, 0)] = -sin / r;
        to_wheels[(i, 1)] = cos / r;
        to_wheels[(i, 2)] = big_r / r;
    }
    let to_twist = to_wheels
        .try_inverse()
        .filter(|m| m.iter().all(|v| v.is_finite()))
        .ok_or(BaseError::Singular)?;
    Ok(Base {
        wheels: wheels.indices,
        names: wheels.names,
        model: Model::Omni3 {
            to_wheels,
            to_twist,
        },
    })
}

fn differential(
    spec: &DifferentialSpec,
    joint_index: &dyn Fn(&str) -> Option<usize>,
) -> Result<Base, BaseError> {
    let radius_m = positive_m("base.differential.wheel_radius_mm", spec.wheel_radius_mm)?;
    let track_m = positive_m("base.differential.track_mm", spec.track_mm)?;
    let mut wheels = Wheels::default();
    wheels.add("base.differential.left".into(), &spec.left, joint_index)?;
    wheels.add("base.differential.right".into(), &spec.right, joint_index)?;
    Ok(Base {
        wheels: wheels.indices,
        names: wheels.names,
        model: Model::Differential { radius_m, track_m },
    })
}

impl Base {
    /// Checks a `base:` section against the robot's joints: `joint_index`
    /// gives the index of a joint by name (`None`: no such joint).
    ///
    /// # Errors
    ///
    /// A [`BaseError`] naming the field: a radius or track not a finite
    /// number > 0, an angle not finite, an unknown joint, two wheels on one
    /// joint, an omni3 base without exactly three wheels or with two wheels
    /// less than [`MIN_SEPARATION_DEG`] apart around the centre.
    pub fn new(
        spec: &BaseSpec,
        joint_index: impl Fn(&str) -> Option<usize>,
    ) -> Result<Base, BaseError> {
        match spec {
            BaseSpec::Omni3(s) => omni3(s, &joint_index),
            BaseSpec::Differential(s) => differential(s, &joint_index),
        }
    }

    /// The joint index of every wheel, in the spec's order (omni3: as
    /// listed; differential: left, right). Wheel speeds use this order.
    pub fn wheels(&self) -> &[usize] {
        &self.wheels
    }

    /// The joint name of every wheel, in the order of [`Base::wheels`].
    pub fn wheel_joints(&self) -> &[String] {
        &self.names
    }

    /// Omni3 or differential.
    pub fn kind(&self) -> BaseKind {
        match self.model {
            Model::Omni3 { .. } => BaseKind::Omni3,
            Model::Differential { .. } => BaseKind::Differential,
        }
    }

    fn check_len(&self, what: &'static str, actual: usize) -> Result<(), BaseError> {
        if actual == self.wheels.len() {
            Ok(())
        } else {
            Err(BaseError::WheelSlice {
                what,
                expected: self.wheels.len(),
                actual,
            })
        }
    }

    /// The wheel speeds (rad/s, in the order of [`Base::wheels`]) that move
    /// the base at `twist`, written into `out`.
    ///
    /// # Errors
    ///
    /// [`BaseError::TwistNotFinite`] for a non-finite component,
    /// [`BaseError::Overflow`] for one so large that a wheel speed is not a
    /// finite number, [`BaseError::Sideways`] when a
    /// differential base is asked for |y| > 1e-9 m/s and
    /// [`BaseError::WheelSlice`] when `out` does not have one entry per
    /// wheel; `out` is then unspecified.
    pub fn wheel_speeds(&self, twist: &Twist, out: &mut [f64]) -> Result<(), BaseError> {
        twist.check_finite()?;
        self.check_len("output", out.len())?;
        match &self.model {
            Model::Omni3 { to_wheels, .. } => {
                let speeds = to_wheels * Vector3::new(twist.x, twist.y, twist.theta);
                out.copy_from_slice(speeds.as_slice());
            }
            Model::Differential { radius_m, track_m } => {
                if twist.y.abs() > SIDEWAYS_TOLERANCE_M_S {
                    return Err(BaseError::Sideways { y: twist.y });
                }
                let turn = twist.theta * track_m / 2.0;
                out[0] = (twist.x - turn) / radius_m;
                out[1] = (twist.x + turn) / radius_m;
            }
        }
        if out.iter().all(|s| s.is_finite()) {
            Ok(())
        } else {
            Err(BaseError::Overflow)
        }
    }

    /// The wheel speeds for `twist`, as [`Base::wheel_speeds`], all scaled
    /// by one factor (at most 1) so that no wheel exceeds its limit
    /// `max_wheel` (rad/s, one per wheel, each > 0): the base keeps its
    /// direction of travel and slows down. Returns the factor; the wheel
    /// that sets it runs exactly at its limit.
    ///
    /// # Errors
    ///
    /// Those of [`Base::wheel_speeds`], [`BaseError::BadLimit`] for a
    /// limit that is not a finite number > 0 and [`BaseError::WheelSlice`]
    /// when `max_wheel` does not have one entry per wheel.
    pub fn limited(
        &self,
        twist: &Twist,
        max_wheel: &[f64],
        out: &mut [f64],
    ) -> Result<f64, BaseError> {
        self.check_len("wheel limits", max_wheel.len())?;
        if let Some((&value, joint)) = max_wheel
            .iter()
            .zip(&self.names)
            .find(|(m, _)| !(m.is_finite() && **m > 0.0))
        {
            return Err(BaseError::BadLimit {
                joint: joint.clone(),
                value,
            });
        }
        self.wheel_speeds(twist, out)?;
        let mut factor = 1.0;
        let mut fastest = None;
        for (i, (s, m)) in out.iter().zip(max_wheel).enumerate() {
            // A wheel at rest gives an infinite ratio: it never decides.
            let ratio = m / s.abs();
            if ratio < factor {
                factor = ratio;
                fastest = Some(i);
            }
        }
        for (s, m) in out.iter_mut().zip(max_wheel) {
            // The clamp only removes rounding: `factor` is the smallest ratio.
            *s = (*s * factor).clamp(-m, *m);
        }
        if let Some(i) = fastest {
            out[i] = max_wheel[i].copysign(out[i]);
        }
        Ok(factor)
    }

    /// The base velocity from measured wheel speeds (rad/s, in the order of
    /// [`Base::wheels`]): the exact inverse of [`Base::wheel_speeds`]. A
    /// differential base's twist has `y = 0`.
    ///
    /// # Errors
    ///
    /// [`BaseError::WheelSlice`] when `wheel_speeds` does not have one entry
    /// per wheel and [`BaseError::BadMeasurement`] for a speed that is not
    /// a finite number.
    pub fn twist(&self, wheel_speeds: &[f64]) -> Result<Twist, BaseError> {
        self.check_len("wheel speeds", wheel_speeds.len())?;
        if let Some((&value, joint)) = wheel_speeds
            .iter()
            .zip(&self.names)
            .find(|(s, _)| !s.is_finite())
        {
            return Err(BaseError::BadMeasurement {
                joint: joint.clone(),
                value,
            });
        }
        Ok(match &self.model {
            Model::Omni3 { to_twist, .. } => {
                let t = to_twist * Vector3::from_column_slice(wheel_speeds);
                Twist {
                    x: t.x,
                    y: t.y,
                    theta: t.z,
                }
            }
            Model::Differential { radius_m, track_m } => {
                let (left, right) = (wheel_speeds[0], wheel_speeds[1]);
                Twist {
                    x: radius_m * (left + right) / 2.0,
                    y: 0.0,
                    theta: radius_m * (right - left) / track_m,
                }
            }
        })
    }
}
