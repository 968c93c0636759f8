//! The ROS 2 side of a serving robot, the way rmw_zenoh lays ROS 2 out on
//! Zenoh (the wire formats are [`crate::ros2`]'s). One ROS node,
//! `servobus_<robot>`, whose entities live under the namespace `<ns>`
//! (`--ros-namespace`, by default the robot's name):
//!
//! | entity | id | kind | type |
//! |---|---|---|---|
//! | `<ns>/joint_states` | 10 | publisher | `sensor_msgs/msg/JointState` |
//! | `<ns>/joint_commands` | 11 | subscription | `sensor_msgs/msg/JointState` |
//! | `<ns>/joint_commands` | 12 | subscription | `std_msgs/msg/Float64MultiArray` |
//! | `<ns>/joint_trajectory` | 13 | subscription | `trajectory_msgs/msg/JointTrajectory` |
//! | `<ns>/follow_joint_trajectory` | 14 to 18 | action server | `control_msgs/action/FollowJointTrajectory` ([`action`]) |
//!
//! Each entity has its liveliness token (so `ros2 topic list`, `ros2
//! action list` and `ros2 node list` see them) and its own GID, the first
//! 16 bytes of the SHA-256 of its token, in the attachment of what it
//! sends.

use std::sync::Arc;

use servobus_robot::config::Units;
use sha2::{Digest, Sha256};
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::Wait;

use super::relay::Inputs;
use super::state::Done;
use super::{zerr, NodeConfig, NodeError, RobotInfo, Shared};
use crate::ros2::{self, types, EntityKind, RosNode, QOS_KEEP_LAST_10};

mod action;
mod topics;
mod trajectory;
mod view;

#[cfg(test)]
mod tests;

use topics::Context;
use trajectory::{Limits, RosRobot};

/// The JointState publisher's entity id (as it was before the inputs came).
const JOINT_STATES_ID: u32 = 10;

/// The first of the action server's five entity ids (send_goal,
/// cancel_goal, get_result, feedback, status).
const ACTION_ID: u32 = 14;

/// The node's ROS 2 entities; dropping them undeclares them.
pub(super) struct Ros2 {
    action: action::Server,
    _subscribers: Vec<Subscriber<()>>,
    joint_states: Publisher<'static>,
    gid: [u8; 16],
    _tokens: Vec<LivelinessToken>,
}

/// The GID of the entity announced by `token`.
fn gid_of(token: &str) -> [u8; 16] {
    let digest = Sha256::digest(token.as_bytes());
    let mut gid = [0u8; 16];
    gid.copy_from_slice(&digest[..16]);
    gid
}

/// The robot as ROS 2 messages address it: names and limits in rad.
fn ros_robot(robot: &RobotInfo) -> RosRobot {
    let limits = robot.joints.iter().map(|name| {
        let config = robot.config.as_ref()?;
        let j = config.joints().find(|j| &j.name == name)?;
        let u = config.units;
        Some(Limits {
            min: u.to_rad(j.min),
            max: u.to_rad(j.max),
            max_velocity: u.to_rad(j.max_velocity),
        })
    });
    RosRobot {
        names: robot.joints.clone(),
        limits: limits.collect(),
        units: robot.units,
    }
}

/// The namespace of the node's entities: `--ros-namespace`, or the
/// robot's name.
pub(super) fn namespace(robot: &str, config: &NodeConfig) -> String {
    match &config.ros_namespace {
        Some(ns) => ros2::ros_namespace(ns),
        None => ros2::ros_namespace(&ros2::ros_name(robot)),
    }
}

impl Ros2 {
    /// Declares the node's ROS 2 entities in `domain`, their callbacks
    /// feeding `to` and sharing `shared`.
    ///
    /// # Errors
    /// [`NodeError::Zenoh`] when one cannot be declared.
    pub(super) fn declare(
        session: &zenoh::Session,
        domain: u32,
        robot: &RobotInfo,
        config: &NodeConfig,
        to: Inputs,
        shared: &Arc<Shared>,
    ) -> Result<Self, NodeError> {
        let zid = session.zid().to_string();
        let ns = namespace(&robot.name, config);
        let name = ros2::node_name(&robot.name);
        let node = RosNode {
            domain,
            session_id: &zid,
            namespace: "",
            name: &name,
        };
        let topic = |t: &str| ros2::name_in(&ns, t);
        let states = topic("joint_states");
        let states_token = node.entity_token(
            JOINT_STATES_ID,
            EntityKind::Publisher,
            &states,
            &types::JOINT_STATE,
            QOS_KEEP_LAST_10,
        );
        let gid = gid_of(&states_token);
        let joint_states = session
            .declare_publisher(ros2::data_key(domain, &states, &types::JOINT_STATE))
            .wait()
            .map_err(zerr)?;
        let cx = Arc::new(Context {
            to,
            shared: Arc::clone(shared),
            robot: ros_robot(robot),
        });
        let subscribers = subscribe(session, domain, &ns, &cx)?;
        let commands = topic("joint_commands");
        let mut tokens = vec![
            node.token(),
            states_token,
            node.subscription_token(11, &commands, &types::JOINT_STATE),
            node.subscription_token(12, &commands, &types::FLOAT64_MULTI_ARRAY),
            node.subscription_token(13, &topic("joint_trajectory"), &types::JOINT_TRAJECTORY),
        ];
        let action_tokens = node.action_server_tokens(ACTION_ID, &topic("follow_joint_trajectory"));
        let gids = action_tokens.clone().map(|t| gid_of(&t));
        let keys = ros2::follow_joint_trajectory_keys(domain, &ns);
        let action = action::Server::declare(session, &keys, (gids, ACTION_ID + 4), &cx)?;
        tokens.extend(action_tokens);
        let mut declared = Vec::new();
        for key in tokens {
            declared.push(
                session
                    .liveliness()
                    .declare_token(key)
                    .wait()
                    .map_err(zerr)?,
            );
        }
        Ok(Ros2 {
            action,
            _subscribers: subscribers,
            joint_states,
            gid,
            _tokens: declared,
        })
    }

    /// Publishes the whole cycle `done` as a JointState (positions
    /// measured, commanded before the first reading; velocities measured),
    /// sequence number `seq`, and the running goal's feedback.
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
        self.joint_states
            .put(js.encode())
            .attachment(ros2::attachment(seq, m.stamp_ns, &self.gid))
            .wait()
            .map_err(zerr)?;
        self.action.feedback(done, units);
        Ok(())
    }

    /// Takes in the whole cycle `done`: the running goal's tolerances.
    pub(super) fn cycle(&self, done: &Done, units: Units) {
        self.action.cycle(done, units);
    }

    /// Ends every goal still running (`why` in its result) and answers
    /// its result.
    pub(super) fn finish(&self, why: &str) {
        self.action.finish(why);
    }
}

/// Subscribes `<ns>/joint_commands` (both types) and
/// `<ns>/joint_trajectory` in `domain`.
fn subscribe(
    session: &zenoh::Session,
    domain: u32,
    ns: &str,
    cx: &Arc<Context>,
) -> Result<Vec<Subscriber<()>>, NodeError> {
    type Take = fn(&[u8], Option<&[u8]>, &Context);
    let [joint_state, multi_array] = ros2::joint_commands_keys(domain, ns);
    let inputs: [(String, Take); 3] = [
        (joint_state, topics::take_joint_state),
        (multi_array, topics::take_multi_array),
        (
            ros2::joint_trajectory_key(domain, ns),
            topics::take_trajectory,
        ),
    ];
    let mut out = Vec::new();
    for (key, take) in inputs {
        let cx = Arc::clone(cx);
        out.push(
            session
                .declare_subscriber(key)
                .callback(move |sample| {
                    let payload = sample.payload().to_bytes();
                    let attachment = sample.attachment().map(|a| a.to_bytes());
                    take(&payload, attachment.as_deref(), &cx);
                })
                .wait()
                .map_err(zerr)?,
        );
    }
    Ok(out)
}
