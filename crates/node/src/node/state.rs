//! The `state` a node publishes: whole cycles gathered from the loop's
//! samples, as JSON (and, with ROS 2 on, as a JointState: [`super::ros`]).

use std::time::SystemTime;

use servobus_robot::odometry::Odometer;
use zenoh::Wait;

use super::{unix_ns, zerr, NodeError, RobotInfo};
use crate::wire::StateMessage;

/// The state of one whole cycle (every bus's joints), angles in the robot
/// file's units.
pub(super) struct Done {
    /// The cycle's number.
    pub(super) cycle: u64,
    /// Its time since the start, s.
    pub(super) t: f64,
    /// The loop's lead (lag compensation) in the cycle, s.
    pub(super) lead: f64,
    /// Per joint, the path at the time of the reading (what the joint
    /// should be at).
    pub(super) planned: Vec<f64>,
    pub(super) msg: StateMessage,
}

impl Done {
    /// Per joint, the goal sent.
    pub(super) fn commanded(&self) -> &[f64] {
        &self.msg.commanded
    }
}

/// Gathers a cycle's samples (one per bus, or more for long buses).
pub(super) struct Watch {
    msg: StateMessage,
    /// Per joint, the path at the time of the reading.
    planned: Vec<f64>,
    /// The lead of the cycle being gathered, s.
    lead: f64,
    /// A mobile base's odometry, for a robot with one.
    odometer: Option<Odometer>,
    cycle: Option<(u64, f64)>,
    /// Faults seen since the last whole cycle.
    pub(super) faults: Vec<String>,
}

impl Watch {
    pub(super) fn new(robot: &RobotInfo) -> Self {
        let n = robot.joints.len();
        Watch {
            msg: StateMessage {
                t: 0.0,
                stamp_ns: 0,
                cycle: 0,
                units: robot.units.name(),
                joints: robot.joints.clone(),
                measured: vec![None; n],
                commanded: vec![0.0; n],
                velocity: vec![0.0; n],
                faults: Vec::new(),
                base_x_m: None,
                base_y_m: None,
                base_theta_deg: None,
            },
            planned: vec![0.0; n],
            lead: 0.0,
            odometer: robot
                .config
                .as_ref()
                .and_then(|r| Odometer::of(r, robot.units)),
            cycle: None,
            faults: Vec::new(),
        }
    }

    /// Takes a sample; returns the previous cycle once a new one begins.
    pub(super) fn cycle(&mut self, c: &servobus_robot::CycleSample) -> Option<Done> {
        let mut done = None;
        if let Some((k, t)) = self.cycle.filter(|(k, _)| *k != c.cycle) {
            let mut msg = self.msg.clone();
            msg.t = t;
            msg.cycle = k;
            msg.stamp_ns = unix_ns(SystemTime::now());
            msg.faults.clone_from(&self.faults);
            done = Some(Done {
                cycle: k,
                t,
                lead: self.lead,
                planned: self.planned.clone(),
                msg,
            });
        }
        self.cycle = Some((c.cycle, c.time_s));
        self.lead = c.lead.as_secs_f64();
        if let Some(o) = self.odometer.as_mut() {
            let pose = o.take(c);
            self.msg.base_x_m = Some(pose.x_m);
            self.msg.base_y_m = Some(pose.y_m);
            self.msg.base_theta_deg = Some(pose.theta_rad.to_degrees());
        }
        for j in c.joints() {
            if j.joint < self.msg.joints.len() {
                self.msg.commanded[j.joint] = j.commanded;
                self.msg.measured[j.joint] = j.measured;
                self.msg.velocity[j.joint] = j.velocity;
                self.planned[j.joint] = j.planned;
            }
        }
        done
    }
}

pub(super) fn publish_state(
    state: &zenoh::pubsub::Publisher<'_>,
    done: &Done,
) -> Result<(), NodeError> {
    let json = serde_json::to_vec(&done.msg).map_err(|e| NodeError::Zenoh(e.to_string()))?;
    state.put(json).wait().map_err(zerr)
}
