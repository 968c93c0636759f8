//! The type descriptions of every interface servobus speaks over rmw_zenoh,
//! as ROS 2 Jazzy defines them (control_msgs 5.x for the action: with the
//! multi-DOF and component-tolerance fields, without the trajectory index
//! control_msgs 6.3 added). Each one's RIHS01 hash is checked against the
//! hash ROS 2 publishes in this module's tests.
//!
//! | interface | description |
//! |---|---|
//! | `sensor_msgs/msg/JointState` | [`JOINT_STATE`] |
//! | `std_msgs/msg/Float64MultiArray` | [`FLOAT64_MULTI_ARRAY`] |
//! | `trajectory_msgs/msg/JointTrajectory` | [`JOINT_TRAJECTORY`] |
//! | `control_msgs/action/FollowJointTrajectory` | [`FOLLOW_JOINT_TRAJECTORY`] |
//! | its `_action/send_goal` service | [`FJT_SEND_GOAL`] |
//! | its `_action/get_result` service | [`FJT_GET_RESULT`] |
//! | its `_action/cancel_goal` service | [`CANCEL_GOAL`] |
//! | its `_action/feedback` topic | [`FJT_FEEDBACK_MESSAGE`] |
//! | its `_action/status` topic | [`GOAL_STATUS_ARRAY`] |

use super::hash::field_type::{
    BOOLEAN, DOUBLE, INT32, INT64, INT8, SEQUENCE, STRING, UINT16, UINT32, UINT8,
};
use super::hash::{array, field, nested, nested_bounded, nested_seq, TypeDescription as T};

/// `builtin_interfaces/msg/Time`.
pub static TIME: T = T::new(
    "builtin_interfaces/msg/Time",
    &[field("sec", INT32), field("nanosec", UINT32)],
);

/// `builtin_interfaces/msg/Duration`.
pub static DURATION: T = T::new(
    "builtin_interfaces/msg/Duration",
    &[field("sec", INT32), field("nanosec", UINT32)],
);

/// `std_msgs/msg/Header`.
pub static HEADER: T = T::new(
    "std_msgs/msg/Header",
    &[nested("stamp", &TIME), field("frame_id", STRING)],
);

/// `sensor_msgs/msg/JointState`.
pub static JOINT_STATE: T = T::new(
    "sensor_msgs/msg/JointState",
    &[
        nested("header", &HEADER),
        field("name", STRING + SEQUENCE),
        field("position", DOUBLE + SEQUENCE),
        field("velocity", DOUBLE + SEQUENCE),
        field("effort", DOUBLE + SEQUENCE),
    ],
);

/// `std_msgs/msg/MultiArrayDimension`.
pub static MULTI_ARRAY_DIMENSION: T = T::new(
    "std_msgs/msg/MultiArrayDimension",
    &[
        field("label", STRING),
        field("size", UINT32),
        field("stride", UINT32),
    ],
);

/// `std_msgs/msg/MultiArrayLayout`.
pub static MULTI_ARRAY_LAYOUT: T = T::new(
    "std_msgs/msg/MultiArrayLayout",
    &[
        nested_seq("dim", &MULTI_ARRAY_DIMENSION),
        field("data_offset", UINT32),
    ],
);

/// `std_msgs/msg/Float64MultiArray`.
pub static FLOAT64_MULTI_ARRAY: T = T::new(
    "std_msgs/msg/Float64MultiArray",
    &[
        nested("layout", &MULTI_ARRAY_LAYOUT),
        field("data", DOUBLE + SEQUENCE),
    ],
);

/// `trajectory_msgs/msg/JointTrajectoryPoint`.
pub static JOINT_TRAJECTORY_POINT: T = T::new(
    "trajectory_msgs/msg/JointTrajectoryPoint",
    &[
        field("positions", DOUBLE + SEQUENCE),
        field("velocities", DOUBLE + SEQUENCE),
        field("accelerations", DOUBLE + SEQUENCE),
        field("effort", DOUBLE + SEQUENCE),
        nested("time_from_start", &DURATION),
    ],
);

/// `trajectory_msgs/msg/JointTrajectory`.
pub static JOINT_TRAJECTORY: T = T::new(
    "trajectory_msgs/msg/JointTrajectory",
    &[
        nested("header", &HEADER),
        field("joint_names", STRING + SEQUENCE),
        nested_seq("points", &JOINT_TRAJECTORY_POINT),
    ],
);

/// `geometry_msgs/msg/Vector3`.
pub static VECTOR3: T = T::new(
    "geometry_msgs/msg/Vector3",
    &[field("x", DOUBLE), field("y", DOUBLE), field("z", DOUBLE)],
);

/// `geometry_msgs/msg/Quaternion`.
pub static QUATERNION: T = T::new(
    "geometry_msgs/msg/Quaternion",
    &[
        field("x", DOUBLE),
        field("y", DOUBLE),
        field("z", DOUBLE),
        field("w", DOUBLE),
    ],
);

/// `geometry_msgs/msg/Transform`.
pub static TRANSFORM: T = T::new(
    "geometry_msgs/msg/Transform",
    &[
        nested("translation", &VECTOR3),
        nested("rotation", &QUATERNION),
    ],
);

/// `geometry_msgs/msg/Twist`.
pub static TWIST: T = T::new(
    "geometry_msgs/msg/Twist",
    &[nested("linear", &VECTOR3), nested("angular", &VECTOR3)],
);

/// `trajectory_msgs/msg/MultiDOFJointTrajectoryPoint`.
pub static MULTI_DOF_POINT: T = T::new(
    "trajectory_msgs/msg/MultiDOFJointTrajectoryPoint",
    &[
        nested_seq("transforms", &TRANSFORM),
        nested_seq("velocities", &TWIST),
        nested_seq("accelerations", &TWIST),
        nested("time_from_start", &DURATION),
    ],
);

/// `trajectory_msgs/msg/MultiDOFJointTrajectory`.
pub static MULTI_DOF_TRAJECTORY: T = T::new(
    "trajectory_msgs/msg/MultiDOFJointTrajectory",
    &[
        nested("header", &HEADER),
        field("joint_names", STRING + SEQUENCE),
        nested_seq("points", &MULTI_DOF_POINT),
    ],
);

/// `unique_identifier_msgs/msg/UUID`.
pub static UUID: T = T::new(
    "unique_identifier_msgs/msg/UUID",
    &[array("uuid", UINT8, 16)],
);

/// `action_msgs/msg/GoalInfo`.
pub static GOAL_INFO: T = T::new(
    "action_msgs/msg/GoalInfo",
    &[nested("goal_id", &UUID), nested("stamp", &TIME)],
);

/// `action_msgs/msg/GoalStatus`.
pub static GOAL_STATUS: T = T::new(
    "action_msgs/msg/GoalStatus",
    &[nested("goal_info", &GOAL_INFO), field("status", INT8)],
);

/// `action_msgs/msg/GoalStatusArray`: the action's `_action/status` topic.
pub static GOAL_STATUS_ARRAY: T = T::new(
    "action_msgs/msg/GoalStatusArray",
    &[nested_seq("status_list", &GOAL_STATUS)],
);

/// `service_msgs/msg/ServiceEventInfo` (its `char[16]` GID is `uint8[16]`
/// in the description, as rosidl maps `char`).
pub static SERVICE_EVENT_INFO: T = T::new(
    "service_msgs/msg/ServiceEventInfo",
    &[
        field("event_type", UINT8),
        nested("stamp", &TIME),
        array("client_gid", UINT8, 16),
        field("sequence_number", INT64),
    ],
);

/// `control_msgs/msg/JointTolerance`.
pub static JOINT_TOLERANCE: T = T::new(
    "control_msgs/msg/JointTolerance",
    &[
        field("name", STRING),
        field("position", DOUBLE),
        field("velocity", DOUBLE),
        field("acceleration", DOUBLE),
    ],
);

/// `control_msgs/msg/JointComponentTolerance`.
pub static JOINT_COMPONENT_TOLERANCE: T = T::new(
    "control_msgs/msg/JointComponentTolerance",
    &[
        field("joint_name", STRING),
        field("component", UINT16),
        field("position", DOUBLE),
        field("velocity", DOUBLE),
        field("acceleration", DOUBLE),
    ],
);

/// `control_msgs/action/FollowJointTrajectory_Goal`.
pub static FJT_GOAL: T = T::new(
    "control_msgs/action/FollowJointTrajectory_Goal",
    &[
        nested("trajectory", &JOINT_TRAJECTORY),
        nested("multi_dof_trajectory", &MULTI_DOF_TRAJECTORY),
        nested_seq("path_tolerance", &JOINT_TOLERANCE),
        nested_seq("component_path_tolerance", &JOINT_COMPONENT_TOLERANCE),
        nested_seq("goal_tolerance", &JOINT_TOLERANCE),
        nested_seq("component_goal_tolerance", &JOINT_COMPONENT_TOLERANCE),
        nested("goal_time_tolerance", &DURATION),
    ],
);

/// `control_msgs/action/FollowJointTrajectory_Result`.
pub static FJT_RESULT: T = T::new(
    "control_msgs/action/FollowJointTrajectory_Result",
    &[field("error_code", INT32), field("error_string", STRING)],
);

/// `control_msgs/action/FollowJointTrajectory_Feedback`.
pub static FJT_FEEDBACK: T = T::new(
    "control_msgs/action/FollowJointTrajectory_Feedback",
    &[
        nested("header", &HEADER),
        field("joint_names", STRING + SEQUENCE),
        nested("desired", &JOINT_TRAJECTORY_POINT),
        nested("actual", &JOINT_TRAJECTORY_POINT),
        nested("error", &JOINT_TRAJECTORY_POINT),
        field("multi_dof_joint_names", STRING + SEQUENCE),
        nested("multi_dof_desired", &MULTI_DOF_POINT),
        nested("multi_dof_actual", &MULTI_DOF_POINT),
        nested("multi_dof_error", &MULTI_DOF_POINT),
    ],
);

/// `control_msgs/action/FollowJointTrajectory_SendGoal_Request`.
pub static FJT_SEND_GOAL_REQUEST: T = T::new(
    "control_msgs/action/FollowJointTrajectory_SendGoal_Request",
    &[nested("goal_id", &UUID), nested("goal", &FJT_GOAL)],
);

/// `control_msgs/action/FollowJointTrajectory_SendGoal_Response`.
pub static FJT_SEND_GOAL_RESPONSE: T = T::new(
    "control_msgs/action/FollowJointTrajectory_SendGoal_Response",
    &[field("accepted", BOOLEAN), nested("stamp", &TIME)],
);

/// `control_msgs/action/FollowJointTrajectory_SendGoal_Event`.
pub static FJT_SEND_GOAL_EVENT: T = T::new(
    "control_msgs/action/FollowJointTrajectory_SendGoal_Event",
    &[
        nested("info", &SERVICE_EVENT_INFO),
        nested_bounded("request", &FJT_SEND_GOAL_REQUEST, 1),
        nested_bounded("response", &FJT_SEND_GOAL_RESPONSE, 1),
    ],
);

/// `control_msgs/action/FollowJointTrajectory_SendGoal`: the
/// `_action/send_goal` service.
pub static FJT_SEND_GOAL: T = T::new(
    "control_msgs/action/FollowJointTrajectory_SendGoal",
    &[
        nested("request_message", &FJT_SEND_GOAL_REQUEST),
        nested("response_message", &FJT_SEND_GOAL_RESPONSE),
        nested("event_message", &FJT_SEND_GOAL_EVENT),
    ],
);

/// `control_msgs/action/FollowJointTrajectory_GetResult_Request`.
pub static FJT_GET_RESULT_REQUEST: T = T::new(
    "control_msgs/action/FollowJointTrajectory_GetResult_Request",
    &[nested("goal_id", &UUID)],
);

/// `control_msgs/action/FollowJointTrajectory_GetResult_Response`.
pub static FJT_GET_RESULT_RESPONSE: T = T::new(
    "control_msgs/action/FollowJointTrajectory_GetResult_Response",
    &[field("status", INT8), nested("result", &FJT_RESULT)],
);

/// `control_msgs/action/FollowJointTrajectory_GetResult_Event`.
pub static FJT_GET_RESULT_EVENT: T = T::new(
    "control_msgs/action/FollowJointTrajectory_GetResult_Event",
    &[
        nested("info", &SERVICE_EVENT_INFO),
        nested_bounded("request", &FJT_GET_RESULT_REQUEST, 1),
        nested_bounded("response", &FJT_GET_RESULT_RESPONSE, 1),
    ],
);

/// `control_msgs/action/FollowJointTrajectory_GetResult`: the
/// `_action/get_result` service.
pub static FJT_GET_RESULT: T = T::new(
    "control_msgs/action/FollowJointTrajectory_GetResult",
    &[
        nested("request_message", &FJT_GET_RESULT_REQUEST),
        nested("response_message", &FJT_GET_RESULT_RESPONSE),
        nested("event_message", &FJT_GET_RESULT_EVENT),
    ],
);

/// `control_msgs/action/FollowJointTrajectory_FeedbackMessage`: the
/// `_action/feedback` topic.
pub static FJT_FEEDBACK_MESSAGE: T = T::new(
    "control_msgs/action/FollowJointTrajectory_FeedbackMessage",
    &[nested("goal_id", &UUID), nested("feedback", &FJT_FEEDBACK)],
);

/// `control_msgs/action/FollowJointTrajectory`: the action itself.
pub static FOLLOW_JOINT_TRAJECTORY: T = T::new(
    "control_msgs/action/FollowJointTrajectory",
    &[
        nested("goal", &FJT_GOAL),
        nested("result", &FJT_RESULT),
        nested("feedback", &FJT_FEEDBACK),
        nested("send_goal_service", &FJT_SEND_GOAL),
        nested("get_result_service", &FJT_GET_RESULT),
        nested("feedback_message", &FJT_FEEDBACK_MESSAGE),
    ],
);

/// `action_msgs/srv/CancelGoal_Request`.
pub static CANCEL_GOAL_REQUEST: T = T::new(
    "action_msgs/srv/CancelGoal_Request",
    &[nested("goal_info", &GOAL_INFO)],
);

/// `action_msgs/srv/CancelGoal_Response`.
pub static CANCEL_GOAL_RESPONSE: T = T::new(
    "action_msgs/srv/CancelGoal_Response",
    &[
        field("return_code", INT8),
        nested_seq("goals_canceling", &GOAL_INFO),
    ],
);

/// `action_msgs/srv/CancelGoal_Event`.
pub static CANCEL_GOAL_EVENT: T = T::new(
    "action_msgs/srv/CancelGoal_Event",
    &[
        nested("info", &SERVICE_EVENT_INFO),
        nested_bounded("request", &CANCEL_GOAL_REQUEST, 1),
        nested_bounded("response", &CANCEL_GOAL_RESPONSE, 1),
    ],
);

/// `action_msgs/srv/CancelGoal`: every action's `_action/cancel_goal`
/// service.
pub static CANCEL_GOAL: T = T::new(
    "action_msgs/srv/CancelGoal",
    &[
        nested("request_message", &CANCEL_GOAL_REQUEST),
        nested("response_message", &CANCEL_GOAL_RESPONSE),
        nested("event_message", &CANCEL_GOAL_EVENT),
    ],
);
