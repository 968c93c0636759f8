//! The `state` a node publishes: whole cycles gathered from the loop's
//! samples, as JSON and (with ROS 2 on) as a JointState.

use std::time::SystemTime;

use servobus_robot::config::Units;
use servobus_robot::odometry::Odometer;
use zenoh::Wait;

use super::{unix_ns, zerr, NodeError, RobotInfo};
use crate::ros2;
use crate::wire::StateMessage;

/// The state of one whole cycle (every bus's joints).
pub(super) struct Done {
    /// The cycle's number.
    pub(super) cycle: u64,
    /// Its time since the start, s.
    pub(super) t: f64,
    msg: StateMessage,
}

/// Gathers a cycle's samples (one per bus, or more for long buses).
pub(super) struct Watch {
    msg: StateMessage,
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
            done = Some(Done { cycle: k, t, msg });
        }
        self.cycle = Some((c.cycle, c.time_s));
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

/// The ROS 2 side: the JointState publisher and its liveliness tokens.
pub(super) struct Ros2 {
    publisher: zenoh::pubsub::Publisher<'static>,
    gid: [u8; 16],
    _tokens: Vec<zenoh::liveliness::LivelinessToken>,
}

impl Ros2 {
    pub(super) fn declare(
        session: &zenoh::Session,
        domain: u32,
        robot: &str,
    ) -> Result<Self, NodeError> {
        let zid = session.zid();
        let id = zid.to_string();
        let mut tokens = Vec::new();
        for key in ros2::liveliness_tokens(domain, &id, robot) {
            tokens.push(
                session
                    .liveliness()
                    .declare_token(key)
                    .wait()
                    .map_err(zerr)?,
            );
        }
        let publisher = session
            .declare_publisher(ros2::joint_states_key(domain, robot))
            .wait()
            .map_err(zerr)?;
        // The publisher's GID: the session's id, which is unique per node.
        let mut gid = [0u8; 16];
        let bytes = zid.to_le_bytes();
        let n = bytes.len().min(16);
        gid[..n].copy_from_slice(&bytes[..n]);
        Ok(Ros2 {
            publisher,
            gid,
            _tokens: tokens,
        })
    }

    pub(super) fn publish(&self, done: &Done, units: Units, seq: i64) -> Result<(), NodeError> {
        let m = &done.msg;
        let position: Vec<f64> = m
            .measured
            .iter()
            .zip(&m.commanded)
            .map(|(meas, cmd)| units.to_rad(meas.unwrap_or(*cmd)))
            .collect();
        let velocity: Vec<f64> = m.velocity.iter().map(|v| units.to_rad(*v)).collect();
        let js = ros2::JointState {
            stamp_ns: m.stamp_ns,
            frame_id: "",
            names: &m.joints,
            position: &position,
            velocity: &velocity,
            effort: &[],
        };
        self.publisher
            .put(js.encode())
            .attachment(ros2::attachment(seq, m.stamp_ns, &self.gid))
            .wait()
            .map_err(zerr)
    }
}
