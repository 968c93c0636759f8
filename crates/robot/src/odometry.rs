//! Where a mobile base has gone: its pose on the floor from the wheels'
//! measured speeds (odometry, from a run's telemetry), and from the
//! simulator's truth of the wheels' angles (the pose it really took).
//!
//! Both integrate the same way: each step's wheel speeds become the base's
//! body velocity ([`Base::twist`]), held over the step, which moves the
//! pose along its arc ([`Odometry::integrate`]). Odometry holds each
//! cycle's measured present speeds until the next cycle; the truth takes
//! each wheel's true turn between two of its samples.

use servobus_config::{Robot, Units};
use servobus_kinematics::Base;
use servobus_runtime::CycleSample;
use servobus_sim::TruthRow;

pub use servobus_kinematics::Odometry;

/// Longest step integrated at once, s: a gap in the telemetry (a paused
/// reader) longer than this is taken as the base having stood still.
const MAX_STEP_S: f64 = 0.25;

/// A base's pose integrated from the measured wheel speeds of a run's
/// telemetry ([`Odometer::take`]); it starts at the origin, heading along
/// the world's x.
#[derive(Debug, Clone)]
pub struct Odometer {
    base: Base,
    /// The base's wheels: their joints in the robot's joint order.
    wheels: Vec<usize>,
    /// The last measured speed of each wheel, rad/s.
    speeds: Vec<f64>,
    /// The telemetry's units (speeds are units/s).
    units: Units,
    /// The time of the last sample integrated, s.
    last: Option<f64>,
    pose: Odometry,
}

impl Odometer {
    /// An odometer of `robot`'s base, for telemetry in `units` (the run's
    /// report units: the robot file's unless the run asked for others);
    /// `None` for a robot without a base.
    pub fn of(robot: &Robot, units: Units) -> Option<Odometer> {
        let base = robot.base.clone()?;
        let wheels = base.wheels().to_vec();
        Some(Odometer {
            speeds: vec![0.0; wheels.len()],
            wheels,
            base,
            units,
            last: None,
            pose: Odometry::default(),
        })
    }

    /// Takes in one bus's cycle: the pose moves on by the wheel speeds
    /// measured so far, held since the last cycle taken, and this cycle's
    /// measured speeds are kept for the next step. A cycle of a bus without
    /// wheels only moves the pose on. Returns the pose.
    pub fn take(&mut self, sample: &CycleSample) -> Odometry {
        let t = sample.time_s;
        match self.last {
            Some(last) if t > last => {
                let dt = t - last;
                if dt <= MAX_STEP_S {
                    self.step(dt);
                }
                self.last = Some(t);
            }
            Some(_) => {}
            None => self.last = Some(t),
        }
        for j in sample.joints() {
            if let Some(w) = self.wheels.iter().position(|&i| i == j.joint) {
                if let (Some(_), Some(s)) = (j.measured, self.speeds.get_mut(w)) {
                    *s = self.units.to_rad(j.velocity);
                }
            }
        }
        self.pose
    }

    fn step(&mut self, dt: f64) {
        if let Ok(twist) = self.base.twist(&self.speeds) {
            // A twist from finite speeds over a positive step integrates.
            let _ = self.pose.integrate(&twist, dt);
        }
    }

    /// The pose so far.
    pub fn pose(&self) -> Odometry {
        self.pose
    }
}

/// A base's true pose, from the simulator's truth rows taken one after
/// another ([`TruthBase::take`]): each wheel's true turn between two rows
/// (angles in degrees) held as its speed over the step. The first row's
/// pose is the origin.
#[derive(Debug, Clone)]
pub struct TruthBase {
    base: Base,
    /// The wheels' columns in the truth, in the base's wheel order.
    columns: Vec<usize>,
    /// The last row's time and wheel angles, deg.
    last: Option<(f64, Vec<f64>)>,
    speeds: Vec<f64>,
    pose: Odometry,
}

impl TruthBase {
    /// The true pose of `robot`'s base from a truth of the joints
    /// `columns`; `None` for a robot without a base, or a truth without
    /// every wheel's column.
    pub fn of(robot: &Robot, columns: &[String]) -> Option<TruthBase> {
        let base = robot.base.clone()?;
        let names: Vec<&str> = robot.joints().map(|j| j.name.as_str()).collect();
        let columns: Option<Vec<usize>> = base
            .wheels()
            .iter()
            .map(|&w| {
                let name = names.get(w)?;
                columns.iter().position(|c| c == name)
            })
            .collect();
        let columns = columns?;
        Some(TruthBase {
            speeds: vec![0.0; columns.len()],
            columns,
            base,
            last: None,
            pose: Odometry::default(),
        })
    }

    /// Takes the next truth row; returns the pose at its time.
    pub fn take(&mut self, row: &TruthRow) -> Odometry {
        let angles: Vec<f64> = self
            .columns
            .iter()
            .map(|&c| row.angles_deg.get(c).copied().unwrap_or(0.0))
            .collect();
        if let Some((t, before)) = &self.last {
            let dt = row.time_s - t;
            if dt > 0.0 {
                for ((s, a), b) in self.speeds.iter_mut().zip(&angles).zip(before) {
                    *s = (a - b).to_radians() / dt;
                }
                if let Ok(twist) = self.base.twist(&self.speeds) {
                    let _ = self.pose.integrate(&twist, dt);
                }
            }
        }
        self.last = Some((row.time_s, angles));
        self.pose
    }
}

/// The base's pose at each of the simulator's truth `rows` (one column
/// per joint in `columns`, angles in degrees), as [`TruthBase`] takes
/// them; `None` as [`TruthBase::of`].
pub fn truth_poses(robot: &Robot, columns: &[String], rows: &[TruthRow]) -> Option<Vec<Odometry>> {
    let mut base = TruthBase::of(robot, columns)?;
    Some(rows.iter().map(|r| base.take(r)).collect())
}

/// A pose's three figures as telemetry and logs give them: x and y in
/// metres, the heading in degrees.
pub fn pose_figures(pose: &Odometry) -> [(&'static str, f64); 3] {
    [
        ("base_x_m", pose.x_m),
        ("base_y_m", pose.y_m),
        ("base_theta_deg", pose.theta_rad.to_degrees()),
    ]
}
