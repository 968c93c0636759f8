//! ROS 2 over rmw_zenoh, the wire side: the CDR payloads, type hashes, key
//! expressions, attachments and liveliness tokens of the topics, services
//! and action servobus speaks. No ROS installation is needed: everything
//! here is computed from the interfaces' definitions, and builds without
//! Zenoh.
//!
//! | name (under the node's namespace) | interface | direction | types |
//! |---|---|---|---|
//! | `joint_states` | `sensor_msgs/msg/JointState` | out | [`JointState`] |
//! | `joint_trajectory` | `trajectory_msgs/msg/JointTrajectory` | in | [`JointTrajectory`] |
//! | `joint_commands` | `sensor_msgs/msg/JointState` or `std_msgs/msg/Float64MultiArray` | in | [`JointStateMessage`], [`Float64MultiArray`] |
//! | `follow_joint_trajectory` | `control_msgs/action/FollowJointTrajectory` | action server | [`follow`], [`action`] |
//!
//! The layout follows rmw_zenoh ([`keys`] has the key and token forms):
//! - payload: CDR, little endian, after the 4-byte encapsulation header
//!   `00 01 00 00` ([`cdr`]);
//! - data key: `<domain>/<fully qualified name>/<DDS type name>/<type hash>`;
//! - attachment: sequence number, source timestamp and GID ([`Attachment`]);
//! - liveliness: `@ros2_lv/...` tokens that make the entities visible to
//!   `ros2 topic list` and `ros2 action list`.
//!
//! The type hash is REP-2016's RIHS01 ([`hash`]), computed from the
//! descriptions in [`types`]; each is checked in the tests against the
//! hash ROS 2 publishes.
//!
//! Decoding never panics: a payload that is not the message is a
//! [`CdrError`] naming the field, and allocates no more than the payload's
//! size allows.
//!
//! ```
//! use servobus_node::ros2::{CdrMessage, JointTrajectory, JointTrajectoryPoint, RosDuration};
//!
//! let sent = JointTrajectory {
//!     joint_names: vec!["elbow_flex".into()],
//!     points: vec![JointTrajectoryPoint {
//!         positions: vec![0.5],
//!         time_from_start: RosDuration::from_secs_f64(1.5),
//!         ..Default::default()
//!     }],
//!     ..Default::default()
//! };
//! let payload = sent.encode();
//! assert_eq!(JointTrajectory::decode(&payload), Ok(sent));
//! assert!(JointTrajectory::decode(&payload[..payload.len() - 1]).is_err());
//! ```

pub mod action;
pub mod cdr;
pub mod follow;
pub mod geometry;
pub mod hash;
pub mod keys;
pub mod msgs;
pub mod types;

pub use action::{
    CancelGoalRequest, CancelGoalResponse, GoalInfo, GoalStatus, GoalStatusArray, Uuid,
};
pub use cdr::{CdrError, CdrErrorKind, CdrMessage, CdrReader, CdrWriter};
pub use follow::{
    FeedbackMessage, FollowJointTrajectoryFeedback, FollowJointTrajectoryGoal,
    FollowJointTrajectoryResult, GetResultRequest, GetResultResponse, JointComponentTolerance,
    JointTolerance, SendGoalRequest, SendGoalResponse,
};
pub use geometry::{
    MultiDofJointTrajectory, MultiDofJointTrajectoryPoint, RosQuaternion, RosTransform, RosTwist,
    RosVector3,
};
pub use hash::TypeDescription;
pub use keys::{
    attachment, data_key, follow_joint_trajectory_keys, joint_commands_keys, joint_state_type_hash,
    joint_states_key, joint_states_topic, joint_trajectory_key, liveliness_tokens, name_in,
    node_name, ros_name, ros_namespace, ActionKeys, Attachment, AttachmentError, EntityKind,
    RosNode, JOINT_STATE_TYPE, QOS_ACTION_STATUS, QOS_KEEP_LAST_10,
};
pub use msgs::{
    Float64MultiArray, Header, JointState, JointStateMessage, JointTrajectory,
    JointTrajectoryPoint, MultiArrayDimension, MultiArrayLayout, RosDuration, RosTime,
};

#[cfg(test)]
mod hash_tests;
#[cfg(test)]
mod keys_tests;
#[cfg(test)]
mod prop_tests;
#[cfg(test)]
mod vector_tests;
