//! servobus as a Zenoh node.
//!
//! A robot's loop, run in live mode, becomes a node of a Zenoh network
//! (peer to peer, no broker). Its keys live under `servobus/<robot>/`:
//!
//! | key | direction | what |
//! |---|---|---|
//! | `state` | out, every few cycles | [`wire::StateMessage`] as JSON |
//! | `target` | in | live targets, `{"joints": {"<name>": angle}}`, a mobile base's velocity `{"base": {"x", "y", "theta"}}`, and action chunks, `{"chunk": {"t0", "dt", "joints": {"<name>": [angle, ...]}}}` |
//! | `command` | in | `play <motion> [at <UTC>]`, `stop`, `pause`, `resume`, `torque_off`, `shutdown` |
//! | `report` | queryable | the run's report as JSON |
//! | `alive` | liveliness token | present while the node runs |
//!
//! `stop` stops the motion (jerk limited) and holds; the node goes on
//! serving, and the next target, chunk or `play` moves the robot again.
//! `shutdown` (or Ctrl-C, or SIGTERM) stops, holds and ends the run; the
//! node answers `report` for its linger, then returns.
//!
//! With ROS 2 on ([`node::NodeConfig::ros2_domain`]), the node is also a
//! ROS 2 node the way rmw_zenoh lays one out ([`ros2`] has the wire
//! formats), under a namespace `<ns>` (by default the robot's name):
//!
//! | ROS 2 name | interface | what the node does |
//! |---|---|---|
//! | `<ns>/joint_states` | `sensor_msgs/msg/JointState` | publishes every state |
//! | `<ns>/joint_trajectory` | `trajectory_msgs/msg/JointTrajectory` | follows it as a timed chunk (a new one replaces the rest of the last) |
//! | `<ns>/joint_commands` | `sensor_msgs/msg/JointState`, `std_msgs/msg/Float64MultiArray` | live targets, as `target`'s |
//! | `<ns>/follow_joint_trajectory` | `control_msgs/action/FollowJointTrajectory` | the action server MoveIt drives: goals, feedback, tolerances, cancel, results |
//!
//! A ROS 2 message that is not what its key carries is counted as
//! malformed, said on stderr and never moves the robot.
//!
//! The wire formats ([`wire`], [`ros2`]) build without Zenoh; the session
//! itself needs the `zenoh` feature.

pub mod ros2;
pub mod wire;

#[cfg(feature = "zenoh")]
pub mod node;

/// The Zenoh crate this node is built on, for programs (and tests) that
/// talk to a node from Rust.
#[cfg(feature = "zenoh")]
pub use zenoh;

/// The key expression prefix of a robot: `servobus/<robot>`.
pub fn prefix(robot: &str) -> String {
    format!("servobus/{}", key_chunk(robot))
}

/// `name` made one chunk of a key expression: no `/`, `*`, `$`, `?`, `#`
/// or whitespace (each becomes `_`), never empty.
pub fn key_chunk(name: &str) -> String {
    let out: String = name
        .chars()
        .map(|c| {
            if c == '/' || c == '*' || c == '$' || c == '?' || c == '#' || c.is_whitespace() {
                '_'
            } else {
                c
            }
        })
        .collect();
    if out.is_empty() {
        "_".into()
    } else {
        out
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn keys_live_under_the_robot() {
        assert_eq!(super::prefix("so101"), "servobus/so101");
        assert_eq!(super::prefix("arm/left *"), "servobus/arm_left__");
        assert_eq!(super::prefix(""), "servobus/_");
    }
}
