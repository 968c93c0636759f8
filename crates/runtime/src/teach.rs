//! Teaching by hand: torque off, a person poses the robot, and the poses
//! (or the whole path) become a motion file that `servobus play` accepts.
//!
//! - [`Teacher`] turns the torque off (except on the joints to hold, which
//!   keep their position) and reads the pose, in the robot file's units.
//! - [`StillCapture`] captures a keyframe each time the robot has moved and
//!   then been held still (pose-and-pause without a keyboard).
//! - [`reduce`] turns a recorded path into the fewest timed keyframes whose
//!   planned path reproduces it within a tolerance, planned exactly as
//!   `play` plans the written file.
//! - [`motion_yaml`] writes the motion file.
//!
//! ```text
//! pose -> [StillCapture] -> keyframes ----------------\
//! path -> [reduce: plan, worst sample, insert, again] -> motion_yaml -> play
//! ```

use std::fmt::Write as _;
use std::path::Path;

use servobus_driver::{Bus, BusError, Clock, Transport};
use servobus_protocol::registers::addr;
use servobus_trajectory::{self as traj, JointState, PlanOptions, TimedShape};

use crate::config::{joint_limits, JointMap, Robot, Units};

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
}

struct TeachJoint {
    name: String,
    bus: usize,
    id: u8,
    map: JointMap,
    hold: bool,
}

/// The robot under a person's hands: torque off, poses read back.
pub struct Teacher<T: Transport, C: Clock> {
    buses: Vec<Bus<T, C>>,
    joints: Vec<TeachJoint>,
    units: Units,
}

impl<T: Transport, C: Clock> Teacher<T, C> {
    /// A teacher of `robot` on `buses` (one per robot bus, in order), holding
    /// the joints named in `hold`.
    ///
    /// # Errors
    /// [`TeachError::UnknownJoint`] for a name in `hold` the robot lacks.
    pub fn new(robot: &Robot, buses: Vec<Bus<T, C>>, hold: &[String]) -> Result<Self, TeachError> {
        let names: Vec<&str> = robot.joints().map(|j| j.name.as_str()).collect();
        if let Some(bad) = hold.iter().find(|h| !names.contains(&h.as_str())) {
            return Err(TeachError::UnknownJoint {
                name: bad.clone(),
                joints: names.join(", "),
            });
        }
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
            let bus = &mut self.buses[j.bus];
            let reg = bus.settings().series.map().get("present_position");
            let ticks = match reg {
                Some(r) => bus.read_register(j.id, r).map(|v| v.0),
                None => Err(BusError::InvalidRequest("no present position register")),
            }
            .map_err(|e| Self::bus_error(j, e))?;
            pose.push(self.units.from_rad(j.map.from_ticks(ticks)));
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
    /// a change under 0.3 deg for 0.7 s, moved is 2 deg from the last
    /// capture (converted to `units`).
    pub fn new(start: &[f64], units: Units) -> StillCapture {
        let deg = |d: f64| units.from_rad(f64::to_radians(d));
        StillCapture {
            still: deg(0.3),
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

/// A timed keyframe: seconds from the start, and every joint's angle in
/// the robot file's units.
pub type TimedPose = (f64, Vec<f64>);

/// The planner options of a reduced path, as its motion file sets them
/// (`interpolation: cubic`, `on_limit: error`): the smooth spline through
/// the keyframes, refused where it breaks a limit. The reduction checks the
/// very plan `play` makes of the file, so the file plays as checked.
fn reduced_options() -> PlanOptions {
    PlanOptions {
        shape: TimedShape::Cubic,
        on_limit: traj::OnLimit::Error,
        ..PlanOptions::default()
    }
}

/// The sample halfway through the longest gap between chosen keyframes.
fn split_longest(chosen: &[usize]) -> Option<(usize, usize)> {
    let (at, gap) = chosen
        .windows(2)
        .enumerate()
        .map(|(k, w)| (k + 1, w[1] - w[0]))
        .max_by_key(|&(_, g)| g)?;
    (gap >= 2).then(|| (at, chosen[at - 1] + gap / 2))
}

/// The fewest timed keyframes (chosen among `samples`) whose planned path
/// stays within `tolerance` (robot units) of every sample, each clamped to
/// the joint limits. Times count from the first sample. Keyframes are
/// added one at a time at the worst-reproduced sample until the path fits
/// (or every sample is a keyframe); where the spline breaks a limit (it
/// swings past a joint limit between keyframes far apart), the longest gap
/// is split first.
pub fn reduce(robot: &Robot, samples: &[TimedPose], tolerance: f64) -> Vec<TimedPose> {
    let Some(first) = samples.first() else {
        return Vec::new();
    };
    let t0 = first.0;
    let limits = joint_limits(robot);
    let units = robot.units;
    let clamp = |p: &[f64]| -> Vec<f64> {
        p.iter()
            .zip(robot.joints())
            .map(|(&v, j)| v.clamp(j.min, j.max))
            .collect()
    };
    let mut chosen = vec![0, samples.len() - 1];
    chosen.dedup();
    let mut state = vec![JointState::default(); robot.joint_count()];
    loop {
        let keyframes: Vec<traj::Keyframe> = chosen
            .iter()
            .map(|&i| {
                let (t, p) = &samples[i];
                let rad: Vec<f64> = clamp(p).iter().map(|&v| units.to_rad(v)).collect();
                let k = traj::Keyframe::new(rad);
                if i == 0 {
                    k
                } else {
                    k.at(t - t0)
                }
            })
            .collect();
        let Ok(path) = traj::plan(&limits, &keyframes, &reduced_options()) else {
            match split_longest(&chosen) {
                Some((at, i)) => {
                    chosen.insert(at, i);
                    continue;
                }
                None => break,
            }
        };
        let mut worst = (0.0, None);
        for (i, (t, p)) in samples.iter().enumerate() {
            path.sample(t - t0, &mut state);
            let err = clamp(p).iter().zip(&state).fold(0.0f64, |m, (v, s)| {
                m.max((v - units.from_rad(s.position)).abs())
            });
            if err > worst.0 {
                worst = (err, Some(i));
            }
        }
        match worst {
            (e, Some(i)) if e > tolerance && !chosen.contains(&i) => {
                let at = chosen.partition_point(|&c| c < i);
                chosen.insert(at, i);
            }
            _ => break,
        }
    }
    chosen
        .iter()
        .map(|&i| (samples[i].0 - t0, clamp(&samples[i].1)))
        .collect()
}

/// A commented motion file for `robot` (loaded from `robot_file`):
/// untimed keyframes (`timed` false: as fast as the limits allow) or timed
/// ones (reduced from a recorded path by [`reduce`], played with
/// `interpolation: cubic`). Angles are
/// clamped to the joint limits and written in the robot's units.
pub fn motion_yaml(
    robot: &Robot,
    robot_file: &Path,
    keyframes: &[TimedPose],
    timed: bool,
    note: &str,
) -> String {
    let mut y = String::new();
    let _ = writeln!(y, "# Taught by hand with `servobus teach`: {note}.");
    let _ = writeln!(
        y,
        "# {} keyframes of every joint of `{}`; edit freely, then `servobus play` this file.",
        keyframes.len(),
        robot.name
    );
    let _ = writeln!(y, "robot: {}", robot_file.display());
    let _ = writeln!(y, "units: {}", robot.units);
    if timed {
        let _ = writeln!(
            y,
            "# `at` is seconds from the first keyframe, as recorded; the spline through the\n\
             # keyframes was checked to stay within the tolerance of the recording and the limits."
        );
        let _ = writeln!(y, "interpolation: cubic");
    } else {
        let _ = writeln!(
            y,
            "# No `at`: each move is as fast as the joint limits allow. Add `at: SECONDS`\n\
             # to a keyframe to time it."
        );
    }
    let _ = writeln!(y, "keyframes:");
    for (k, (t, pose)) in keyframes.iter().enumerate() {
        let mut line = String::from("  - ");
        if timed && k > 0 {
            let _ = write!(line, "at: {t:.3}\n    ");
        }
        line.push_str("pose: {");
        for (i, (v, j)) in pose.iter().zip(robot.joints()).enumerate() {
            let sep = if i == 0 { "" } else { ", " };
            let _ = write!(line, "{sep}{}: {:.2}", j.name, v.clamp(j.min, j.max));
        }
        line.push('}');
        let _ = writeln!(y, "{line}");
    }
    y
}
