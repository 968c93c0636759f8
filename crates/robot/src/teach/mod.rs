//! Teaching by hand: torque off, a person poses the robot, and the poses
//! (or the whole path) become a motion file that `servobus play` accepts.
//!
//! - [`Teacher`] turns the torque off (except on the joints to hold, which
//!   keep their position) and reads the pose, in the robot file's units.
//! - [`StillCapture`] captures a keyframe each time the robot has moved and
//!   then been held still (pose-and-pause without a keyboard).
//! - [`check_pose`] refuses a pose outside the joint limits: a taught
//!   angle is never clamped, the take stops and says which joint, where,
//!   and whose limit (the robot file's or the calibration's).
//! - [`Taught::paced`] keeps pose-and-pause keyframes at the times they were
//!   captured, from the starting pose, so that the motion replays at the
//!   pace it was taught (or says in the file why it cannot).
//! - [`Taught::continuous`] trims the idle time at both ends of a recorded
//!   path and [`reduce`]s it to the fewest timed keyframes whose planned
//!   path reproduces it within a tolerance, planned exactly as `play` plans
//!   the written file; a take interrupted while the robot moved gets time
//!   to come to rest at its last pose.
//! - [`motion_yaml`] writes the motion file.
//!
//! ```text
//! pose -> [check_pose] -> [StillCapture] -> keyframes -> [Taught::paced] ------\
//! path -> [check_pose] -> [trim_idle] -> [reduce: plan, worst, insert] -> [Taught::continuous]
//!                                                         -> motion_yaml -> play
//! ```

use servobus_driver::{Bus, BusError, Clock, Transport};
use servobus_protocol::registers::addr;

use crate::config::{JointMap, Robot, Units};

mod take;
mod taught;

pub use take::Take;

pub use taught::{
    check_pose, merge_identical, motion_yaml, reduce, trim_idle, Reduced, Taught, TimedPose,
    IDLE_KEPT_S,
};

/// Why teaching failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TeachError {
    /// A joint to hold is not in the robot.
    #[error("no joint `{name}` to hold (joints: {joints})")]
    UnknownJoint {
        /// The name given.
        name: String,
        /// The robot's joints.
        joints: String,
    },
    /// The servos do not match the robot's calibration (nothing was
    /// released or read through it).
    #[error(transparent)]
    Refused(#[from] crate::calibrate::Refusal),
    /// A bus transaction with a joint's servo failed.
    #[error("joint `{joint}` (ID {id}): {source}")]
    Bus {
        /// The joint.
        joint: String,
        /// Its servo's ID.
        id: u8,
        /// What the bus said.
        #[source]
        source: BusError,
    },
    /// A taught pose puts a joint outside its limits (it is not clamped).
    #[error(
        "joint `{joint}` was taught at {value:.1} {units}, outside its limits \
         [{min:.1}, {max:.1}] {units} (the {} limit comes from {})",
        if *value < *min { "lower" } else { "upper" },
        origin
    )]
    OutsideLimits {
        /// The joint.
        joint: String,
        /// The angle read, in the robot file's units.
        value: f64,
        /// The joint's lower limit.
        min: f64,
        /// The joint's upper limit.
        max: f64,
        /// The robot file's angle unit.
        units: Units,
        /// Where the limit that was passed comes from.
        origin: crate::config::LimitOrigin,
    },
    /// No timing of the recorded path plays within the joint limits, even
    /// with time to come to rest at its end.
    #[error("the recorded path cannot be played within the joint limits: {reason}")]
    Unplayable {
        /// The planner's last refusal.
        reason: String,
    },
}

struct TeachJoint {
    name: String,
    bus: usize,
    id: u8,
    map: JointMap,
    hold: bool,
}

/// The robot under a person's hands: torque off, poses read back.
pub struct Teacher<T: Transport> {
    buses: Vec<Bus<T>>,
    joints: Vec<TeachJoint>,
    units: Units,
}

impl<T: Transport> Teacher<T> {
    /// A teacher of `robot` on `buses` (one per robot bus, in order), holding
    /// the joints named in `hold`. The servos are first made to match the
    /// robot's calibration ([`prepare_servos`](crate::calibrate::prepare_servos)),
    /// so that a pose reads the same angles as `play` moves to.
    ///
    /// # Errors
    /// [`TeachError::UnknownJoint`] for a name in `hold` the robot lacks;
    /// [`TeachError::Refused`] when the servos do not match the calibration.
    pub fn new(robot: &Robot, mut buses: Vec<Bus<T>>, hold: &[String]) -> Result<Self, TeachError> {
        let names: Vec<&str> = robot.joints().map(|j| j.name.as_str()).collect();
        if let Some(bad) = hold.iter().find(|h| !names.contains(&h.as_str())) {
            return Err(TeachError::UnknownJoint {
                name: bad.clone(),
                joints: names.join(", "),
            });
        }
        crate::calibrate::prepare_servos(robot, &mut buses)?;
        let mut joints = Vec::new();
        for (b, bus) in robot.buses.iter().enumerate() {
            for j in &bus.joints {
                joints.push(TeachJoint {
                    name: j.name.clone(),
                    bus: b,
                    id: j.id,
                    map: JointMap::new(j, robot.units),
                    hold: hold.contains(&j.name),
                });
            }
        }
        Ok(Teacher {
            buses,
            joints,
            units: robot.units,
        })
    }

    fn bus_error(j: &TeachJoint, source: BusError) -> TeachError {
        TeachError::Bus {
            joint: j.name.clone(),
            id: j.id,
            source,
        }
    }

    /// Turns the torque off on every joint but the held ones, which get
    /// their present position as goal and then torque on, so that they stay
    /// exactly where they are.
    ///
    /// # Errors
    /// [`TeachError::Bus`] for the first servo that does not answer.
    pub fn release(&mut self) -> Result<(), TeachError> {
        for j in &self.joints {
            let bus = &mut self.buses[j.bus];
            let result = if j.hold {
                let mut b = [0u8; 2];
                bus.read(j.id, addr::PRESENT_POSITION, &mut b)
                    .and_then(|_| bus.write(j.id, addr::GOAL_POSITION, &b))
                    .and_then(|_| bus.write(j.id, addr::TORQUE_ENABLE, &[1]))
            } else {
                bus.write(j.id, addr::TORQUE_ENABLE, &[0])
            };
            result.map_err(|e| Self::bus_error(j, e))?;
        }
        Ok(())
    }

    /// The pose now: every joint's angle in the robot file's units.
    ///
    /// # Errors
    /// [`TeachError::Bus`] for the first servo that does not answer.
    pub fn pose(&mut self) -> Result<Vec<f64>, TeachError> {
        let mut pose = Vec::with_capacity(self.joints.len());
        for j in &self.joints {
            let angle = read_angle(&mut self.buses[j.bus], j.id, &j.map)
                .map_err(|e| Self::bus_error(j, e))?;
            pose.push(self.units.from_rad(angle));
        }
        Ok(pose)
    }

    /// The time now on the first bus's clock.
    pub fn now(&self) -> std::time::Duration {
        self.buses
            .first()
            .map(|b| b.clock().now())
            .unwrap_or_default()
    }

    /// Waits until `deadline` on every bus's clock.
    pub fn sleep_until(&self, deadline: std::time::Duration) {
        for b in &self.buses {
            b.clock().sleep_until(deadline);
        }
    }

    /// The names of the joints, in the robot's joint order.
    pub fn joint_names(&self) -> Vec<String> {
        self.joints.iter().map(|j| j.name.clone()).collect()
    }
}

/// The angle (radians) of the joint that `map` maps, read from the present
/// position of its servo `id` on `bus`: what a pose of [`Teacher::pose`] or
/// a leader arm's reading is made of.
///
/// # Errors
/// The bus's; [`BusError::InvalidRequest`] when the bus's series has no
/// present position register.
pub fn read_angle<T: Transport>(bus: &mut Bus<T>, id: u8, map: &JointMap) -> Result<f64, BusError> {
    let register = bus
        .settings()
        .series
        .map()
        .get("present_position")
        .ok_or(BusError::InvalidRequest("no present position register"))?;
    let (ticks, _) = bus.read_register(id, register)?;
    Ok(map.from_ticks(ticks))
}

/// Below this change, degrees, a robot under a person's hand counts as
/// still (a hand's tremor and a servo's last tick stay under it).
pub const STILL_DEG: f64 = 0.3;

/// Largest absolute difference between two poses.
pub fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0, |m, (x, y)| m.max((x - y).abs()))
}

/// Captures a keyframe each time the robot has moved and then been held
/// still: pose-and-pause without a keyboard.
#[derive(Debug, Clone)]
pub struct StillCapture {
    /// Below this change (robot units) the robot counts as still.
    pub still: f64,
    /// How long it must be still, s.
    pub still_for_s: f64,
    /// How far (robot units) it must have moved from the last capture.
    pub moved: f64,
    /// Start of the present still window: time and pose.
    anchor: Option<(f64, Vec<f64>)>,
    last: Vec<f64>,
}

impl StillCapture {
    /// A detector that starts from `start` (not captured itself): still is
    /// a change under [`STILL_DEG`] for 0.7 s, moved is 2 deg from the last
    /// capture (converted to `units`).
    pub fn new(start: &[f64], units: Units) -> StillCapture {
        let deg = |d: f64| units.from_rad(f64::to_radians(d));
        StillCapture {
            still: deg(STILL_DEG),
            still_for_s: 0.7,
            moved: deg(2.0),
            anchor: None,
            last: start.to_vec(),
        }
    }

    /// Feeds the pose at `t` seconds; returns it when it is a new keyframe.
    pub fn push(&mut self, t: f64, pose: &[f64]) -> Option<Vec<f64>> {
        match &self.anchor {
            Some((_, a)) if distance(a, pose) <= self.still => {}
            _ => self.anchor = Some((t, pose.to_vec())),
        }
        let (since, _) = self.anchor.as_ref()?;
        if t - since >= self.still_for_s && distance(&self.last, pose) > self.moved {
            self.last = pose.to_vec();
            return Some(pose.to_vec());
        }
        None
    }

    /// Marks `pose` as captured (by a key press, say).
    pub fn captured(&mut self, pose: &[f64]) {
        self.last = pose.to_vec();
    }

    /// The last captured pose (or the start).
    pub fn last(&self) -> &[f64] {
        &self.last
    }
}
