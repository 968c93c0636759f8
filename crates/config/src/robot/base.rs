//! A robot's mobile base as targets see it: a base velocity becomes speed
//! targets for its wheel joints, all scaled together within the wheels'
//! speed limits so that the base keeps its direction of travel.

use servobus_kinematics::{BaseError, Twist};

use super::Robot;

/// A velocity asked of a robot's mobile base, in the base's frame (x
/// forward, y left, theta counter-clockwise).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BaseTarget {
    /// Forward speed, m/s.
    pub x: f64,
    /// Leftward speed, m/s.
    pub y: f64,
    /// Turning speed, the robot file's units per second (deg/s in a
    /// `units: deg` file).
    pub theta: f64,
}

/// Why a base velocity cannot be driven.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BaseTargetError {
    /// The robot has no `base:` section.
    #[error("robot `{0}` has no mobile base: a `base:` section in its robot file makes its wheel joints one")]
    NoBase(String),
    /// The base cannot move so (a differential base sideways, a speed
    /// that is not a number).
    #[error("{0}")]
    Base(#[from] BaseError),
}

/// The wheel speed targets of a base velocity: per wheel joint, its name
/// and speed (rad/s of the wheel), and the factor (at most 1) every wheel
/// was scaled by to keep within its limit.
#[derive(Debug, Clone, PartialEq)]
pub struct WheelTargets {
    /// `(wheel joint, rad/s)`, in the base's wheel order.
    pub wheels: Vec<(String, f64)>,
    /// The scale all wheels took (1: none was beyond its limit).
    pub scale: f64,
}

impl Robot {
    /// The wheel speeds that drive this robot's base at `target`, scaled
    /// together so that no wheel exceeds its `max_velocity`.
    ///
    /// # Errors
    /// [`BaseTargetError::NoBase`] without a `base:` section;
    /// [`BaseTargetError::Base`] for a velocity the base cannot take (a
    /// differential base moving sideways, a number that is not finite).
    pub fn wheel_targets(&self, target: &BaseTarget) -> Result<WheelTargets, BaseTargetError> {
        let base = self
            .base
            .as_ref()
            .ok_or_else(|| BaseTargetError::NoBase(self.name.clone()))?;
        let joints: Vec<_> = self.joints().collect();
        let mut names = Vec::with_capacity(base.wheels().len());
        let mut limits = Vec::with_capacity(base.wheels().len());
        for &w in base.wheels() {
            // The base was checked against these joints when it was read.
            if let Some(j) = joints.get(w) {
                names.push(j.name.clone());
                limits.push(self.units.to_rad(j.max_velocity));
            }
        }
        let twist = Twist {
            x: target.x,
            y: target.y,
            theta: self.units.to_rad(target.theta),
        };
        let mut speeds = vec![0.0; limits.len()];
        let scale = base.limited(&twist, &limits, &mut speeds)?;
        Ok(WheelTargets {
            wheels: names.into_iter().zip(speeds).collect(),
            scale,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{load_robot, RobotOptions, RobotSource};
    use std::path::Path;

    /// A differential base: wheels `l` (ID 1) and `r` (ID 2) at 180 deg/s
    /// at most, 50 mm wheels, 200 mm apart.
    fn robot(base: bool) -> Robot {
        let wheel = |name: &str, id: u8| {
            format!(
                "      - {{name: {name}, id: {id}, model: sts3215, mode: wheel, max_velocity: 180, \
                 max_acceleration: 900}}\n"
            )
        };
        let mut text = format!(
            "name: cart\nunits: deg\nbuses:\n  - name: b\n    joints:\n{}{}",
            wheel("l", 1),
            wheel("r", 2)
        );
        if base {
            text.push_str(
                "base:\n  differential: {wheel_radius_mm: 50, track_mm: 200, left: l, right: r}\n",
            );
        }
        let source = RobotSource::Text {
            name: Path::new("<text>"),
            text: &text,
        };
        load_robot(source, &RobotOptions::default()).expect("the cart loads")
    }

    #[test]
    fn a_base_velocity_becomes_wheel_speeds_scaled_together_within_their_limits() {
        let cart = robot(true);
        // 0.1 m/s forward: both wheels at 2 rad/s, within pi rad/s.
        let slow = cart
            .wheel_targets(&BaseTarget {
                x: 0.1,
                ..BaseTarget::default()
            })
            .expect("wheel speeds");
        assert_eq!(slow.scale, 1.0);
        for (name, (n, w)) in ["l", "r"].iter().zip(&slow.wheels) {
            assert_eq!(name, n);
            assert!((w - 2.0).abs() < 1e-9, "{w}");
        }
        // Forward and turning, too fast for the right wheel: both slowed by
        // one factor, the right wheel at its limit, the ratio kept.
        let fast = cart
            .wheel_targets(&BaseTarget {
                x: 0.2,
                y: 0.0,
                theta: 90.0,
            })
            .expect("wheel speeds");
        let (l, r) = (fast.wheels[0].1, fast.wheels[1].1);
        assert!(fast.scale < 1.0);
        assert!((r - std::f64::consts::PI).abs() < 1e-9, "{r}");
        // Unscaled: l = (0.2 - 0.1 * pi / 2) / 0.05, r = (0.2 + 0.1 * pi / 2) / 0.05.
        let (l0, r0) = (
            (0.2 - 0.1 * std::f64::consts::FRAC_PI_2) / 0.05,
            (0.2 + 0.1 * std::f64::consts::FRAC_PI_2) / 0.05,
        );
        assert!((l / r - l0 / r0).abs() < 1e-9, "{l} {r}");
    }

    #[test]
    fn a_robot_without_a_base_or_a_sideways_cart_is_refused_saying_why() {
        let e = robot(false)
            .wheel_targets(&BaseTarget::default())
            .expect_err("no base");
        assert!(e.to_string().contains("no mobile base"), "{e}");
        let e = robot(true)
            .wheel_targets(&BaseTarget {
                y: 0.1,
                ..BaseTarget::default()
            })
            .expect_err("sideways");
        assert!(e.to_string().contains("sideways"), "{e}");
    }
}
