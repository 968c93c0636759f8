//! Where the robot is in the world: a legged robot's body moves over the
//! feet it stands on, so its pose is integrated from them, sample to
//! sample (the feet on the ground stay where they are; seen from the body
//! they move by the inverse of its move); an arm's base stays where it is.
//! And the paths of the tool and the feet in the world.

use servobus_kinematics::{move_on_feet, Isometry3, Point3, UnitQuaternion, Vector2, Vector3};

/// A planned (or commanded) foot this close to the ground plane stands on
/// it, mm: the plan puts it exactly there, and a foot lifting off or
/// landing, which already slides with its step, is farther.
pub(super) const PLANNED_ON_GROUND_MM: f64 = 0.05;

/// A measured foot this close to the ground plane stands on it, mm: within
/// the servos' resolution (one STS3215 tick moves a hexapod's foot 0.4 mm
/// at most); a stepping foot rises tens of mm.
pub(super) const MEASURED_ON_GROUND_MM: f64 = 1.0;

/// The steepest plane through three feet that is taken for the ground,
/// deg: a body leans over its feet by some degrees, while three feet of
/// one side nearly in a line make planes of any slope.
const MAX_LEAN_DEG: f64 = 30.0;

/// A path keeps a point at most every this far, mm.
const PATH_STEP_MM: f64 = 0.5;

/// The most points a path keeps: past it, every other point is dropped
/// and the step doubles (an hour of live following stays a few MB).
const PATH_POINTS: usize = 20_000;

/// A legged body's pose in the world, from its feet.
#[derive(Debug, Clone)]
pub(super) struct Odometer {
    /// x, y (mm) and heading (rad) in the frame the body started in.
    x: f64,
    y: f64,
    heading: f64,
    /// Each foot on the ground at the last sample (x, y in the body
    /// frame); `None`: in the air, or no sample yet.
    before: Vec<Option<Vector2<f64>>>,
    /// How close to the ground plane a foot stands on it, mm.
    on_ground_mm: f64,
}

impl Odometer {
    /// An odometer of `feet` feet at the world's origin, a foot standing
    /// within `on_ground_mm` of the ground ([`PLANNED_ON_GROUND_MM`],
    /// [`MEASURED_ON_GROUND_MM`]).
    pub(super) fn new(feet: usize, on_ground_mm: f64) -> Odometer {
        Odometer {
            x: 0.0,
            y: 0.0,
            heading: 0.0,
            before: vec![None; feet],
            on_ground_mm,
        }
    }

    /// Takes the feet at a new sample (body frame, mm) in: with at least
    /// three on the ground now and at the last sample, the body has moved
    /// by what takes them from here to there. Returns the body's pose in
    /// the world, mm.
    pub(super) fn step(&mut self, feet: &[Point3<f64>]) -> Isometry3<f64> {
        let down = on_ground(feet, self.on_ground_mm);
        let now: Vec<Option<Vector2<f64>>> = feet
            .iter()
            .zip(&down)
            .map(|(p, &d)| d.then(|| Vector2::new(p.x, p.y)))
            .collect();
        if let Some((angle, shift)) = move_on_feet(&now, &self.before) {
            let (s, c) = self.heading.sin_cos();
            self.x += c * shift.x - s * shift.y;
            self.y += s * shift.x + c * shift.y;
            self.heading += angle;
        }
        self.before = now;
        self.pose()
    }

    /// The body's pose in the world, mm: on the ground plane, turned by
    /// its heading.
    pub(super) fn pose(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Vector3::new(self.x, self.y, 0.0).into(),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), self.heading),
        )
    }
}

/// Which of `feet` (body frame, mm) stand on the ground (within
/// `tolerance` mm of it): those on the plane through three of them that
/// has no foot under it, the most feet on it, and of those the most
/// level. The ground is a plane, not a height: a body that rises or leans
/// over its feet moves it in its frame.
pub(super) fn on_ground(feet: &[Point3<f64>], tolerance: f64) -> Vec<bool> {
    let n = feet.len();
    let mut best: (usize, f64, Vec<bool>) = (0, 0.0, vec![false; n]);
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                let normal = (feet[j] - feet[i]).cross(&(feet[k] - feet[i]));
                let len = normal.norm();
                if len < 1e-6 {
                    continue; // three feet in a line make no plane
                }
                // Up: the ground is under the body, whichever way it leans.
                let normal = normal * normal.z.signum() / len;
                if normal.z < MAX_LEAN_DEG.to_radians().cos() {
                    continue;
                }
                let height: Vec<f64> = feet.iter().map(|p| (p - feet[i]).dot(&normal)).collect();
                if height.iter().any(|&h| h < -tolerance) {
                    continue;
                }
                let down: Vec<bool> = height.iter().map(|h| h.abs() < tolerance).collect();
                let count = down.iter().filter(|&&d| d).count();
                if count > best.0 || (count == best.0 && normal.z > best.1) {
                    best = (count, normal.z, down);
                }
            }
        }
    }
    best.2
}

/// A path in the world, mm: points at least [`PATH_STEP_MM`] apart (the
/// step grows past [`PATH_POINTS`] points).
#[derive(Debug, Clone, Default)]
pub(super) struct Trace {
    points: Vec<Point3<f64>>,
    step_mm: f64,
}

impl Trace {
    /// Adds `p` when it is far enough from the last point kept.
    pub(super) fn push(&mut self, p: Point3<f64>) {
        let step = self.step_mm.max(PATH_STEP_MM);
        if self.points.last().is_some_and(|l| (p - l).norm() < step) {
            return;
        }
        self.points.push(p);
        if self.points.len() >= PATH_POINTS {
            let kept: Vec<Point3<f64>> = self.points.iter().step_by(2).copied().collect();
            self.points = kept;
            self.step_mm = step * 2.0;
        }
    }

    /// The points, metres, single precision.
    pub(super) fn metres(&self) -> Vec<[f32; 3]> {
        self.points
            .iter()
            .map(|p| [p.x, p.y, p.z].map(super::tree::mm_to_m))
            .collect()
    }

    /// Whether it has fewer than two points (no line to draw).
    pub(super) fn is_short(&self) -> bool {
        self.points.len() < 2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Six feet of a standing hexapod, 80 mm under its body, shifted by
    /// `shift` (mm) and turned by `turn` (rad) in the body's frame.
    fn stance(shift: Vector2<f64>, turn: f64) -> Vec<Point3<f64>> {
        let (s, c) = turn.sin_cos();
        (0..6)
            .map(|k| {
                let a = k as f64 * std::f64::consts::PI / 3.0;
                let (x, y) = (200.0 * a.cos(), 150.0 * a.sin());
                Point3::new(c * x - s * y + shift.x, s * x + c * y + shift.y, -80.0)
            })
            .collect()
    }

    #[test]
    fn a_body_walking_over_planted_feet_moves_by_their_inverse() {
        let mut odometer = Odometer::new(6, PLANNED_ON_GROUND_MM);
        // The body goes 10 mm forward and turns 1 deg a sample: its feet
        // go back and turn the other way in its frame.
        let (mut x, mut y, mut heading) = (0.0f64, 0.0f64, 0.0f64);
        let mut world = Vec::new();
        for k in 0..90 {
            let shift = Vector2::new(-x, -y);
            let (s, c) = (-heading).sin_cos();
            let rotated = Vector2::new(c * shift.x - s * shift.y, s * shift.x + c * shift.y);
            let feet = stance(rotated, -heading);
            let pose = odometer.step(&feet);
            world.push(pose);
            assert!((pose.translation.x - x).abs() < 1e-6, "sample {k}");
            assert!((pose.translation.y - y).abs() < 1e-6, "sample {k}");
            let (s, c) = heading.sin_cos();
            x += 10.0 * c;
            y += 10.0 * s;
            heading += 1f64.to_radians();
        }
        let end = world.last().expect("samples").rotation.euler_angles().2;
        assert!(
            (end.to_degrees() - 89.0).abs() < 1e-6,
            "{}",
            end.to_degrees()
        );
    }

    #[test]
    fn a_stepping_foot_is_off_the_ground_and_a_leaning_body_still_stands() {
        let mut feet = stance(Vector2::zeros(), 0.0);
        feet[1].z += 25.0;
        feet[3].z += 25.0;
        let measured = MEASURED_ON_GROUND_MM;
        assert_eq!(
            on_ground(&feet, measured),
            [true, false, true, false, true, true]
        );
        // Leaning 10 deg: the ground is the tilted plane of all six.
        let lean = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 10f64.to_radians());
        let leaning: Vec<Point3<f64>> = stance(Vector2::zeros(), 0.0)
            .iter()
            .map(|p| lean * p)
            .collect();
        assert!(on_ground(&leaning, measured).iter().all(|&d| d));
    }

    #[test]
    fn a_long_path_keeps_its_shape_in_bounded_points() {
        let mut trace = Trace::default();
        for k in 0..200_000 {
            let t = f64::from(k) * 1e-3;
            trace.push(Point3::new(100.0 * t.cos(), 100.0 * t.sin(), t));
        }
        let points = trace.metres();
        assert!(points.len() < PATH_POINTS, "{}", points.len());
        assert!(points.len() > PATH_POINTS / 4, "{}", points.len());
        assert!(!trace.is_short());
    }
}

#[cfg(test)]
mod walk_tests {
    use super::*;
    use servobus_kinematics::{Legs, Poses};
    use servobus_trajectory::JointState;

    #[test]
    fn the_planned_walk_and_turn_ends_400_mm_ahead_turned_90_deg() {
        let robot = crate::Robot::open("hexapod").expect("built-in robot");
        let motion = robot.motion("hexapod-walk-turn").expect("built-in motion");
        let path = robot.plan(&motion).expect("plans");
        let geometry = robot.config().geometry().expect("geometry");
        let legs = Legs::new(&geometry).expect("legs");
        let mut poses = Poses::new(&geometry);
        let mut feet = vec![Point3::origin(); legs.len()];
        let mut state = vec![JointState::default(); path.joints()];
        let mut odometer = Odometer::new(legs.len(), PLANNED_ON_GROUND_MM);
        let samples = (path.duration() / 0.01).ceil() as usize;
        for k in 0..=samples {
            path.sample((k as f64 * 0.01).min(path.duration()), &mut state);
            let q: Vec<f64> = state.iter().map(|s| s.position).collect();
            legs.feet(&q, &mut poses, &mut feet);
            odometer.step(&feet);
        }
        // 300 mm forward, a quarter turn left on the spot, then 100 mm to
        // the body's right: the world's +x again.
        let end = odometer.pose();
        let (x, y) = (end.translation.x, end.translation.y);
        assert!(
            (x - 400.0).abs() < 5.0 && y.abs() < 5.0,
            "{x:.1}, {y:.1} mm"
        );
        let turn = end.rotation.euler_angles().2.to_degrees();
        assert!((turn - 90.0).abs() < 0.2, "{turn:.2} deg");
    }
}
