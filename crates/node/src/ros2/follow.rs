//! `control_msgs/action/FollowJointTrajectory` as rmw_zenoh carries it: the
//! action's goal, result and feedback, and the messages of its services
//! and topics (ROS 2 Jazzy, control_msgs 5.x).
//!
//! | under `<ns>/follow_joint_trajectory/_action/` | kind | request / message | response |
//! |---|---|---|---|
//! | `send_goal` | service | [`SendGoalRequest`] | [`SendGoalResponse`] |
//! | `get_result` | service | [`GetResultRequest`] | [`GetResultResponse`] |
//! | `cancel_goal` | service | [`CancelGoalRequest`](super::action::CancelGoalRequest) | [`CancelGoalResponse`](super::action::CancelGoalResponse) |
//! | `feedback` | topic | [`FeedbackMessage`] | |
//! | `status` | topic | [`GoalStatusArray`](super::action::GoalStatusArray) | |

use super::action::Uuid;
use super::cdr::{CdrError, CdrMessage, CdrReader, CdrWriter};
use super::geometry::{MultiDofJointTrajectory, MultiDofJointTrajectoryPoint};
use super::hash::TypeDescription;
use super::msgs::{Header, JointTrajectory, JointTrajectoryPoint, RosDuration, RosTime};
use super::types;

/// `control_msgs/msg/JointTolerance`: how far a joint may be from the
/// trajectory. 0 means "the server's default", -1 "no limit".
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointTolerance {
    /// The joint.
    pub name: String,
    /// Position (rad or m).
    pub position: f64,
    /// Velocity.
    pub velocity: f64,
    /// Acceleration.
    pub acceleration: f64,
}

impl CdrMessage for JointTolerance {
    const MIN_WIRE_SIZE: usize = 29;
    fn description() -> &'static TypeDescription {
        &types::JOINT_TOLERANCE
    }
    fn write(&self, w: &mut CdrWriter) {
        w.string(&self.name);
        w.f64(self.position);
        w.f64(self.velocity);
        w.f64(self.acceleration);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(JointTolerance {
            name: r.string("name")?,
            position: r.f64("position")?,
            velocity: r.f64("velocity")?,
            acceleration: r.f64("acceleration")?,
        })
    }
}

/// `control_msgs/msg/JointComponentTolerance`: a tolerance on one
/// component of a multi-DOF joint.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointComponentTolerance {
    /// The joint.
    pub joint_name: String,
    /// Which component: one of the constants below.
    pub component: u16,
    /// Position.
    pub position: f64,
    /// Velocity.
    pub velocity: f64,
    /// Acceleration.
    pub acceleration: f64,
}

impl JointComponentTolerance {
    /// Along x.
    pub const X_AXIS: u16 = 1;
    /// Along y.
    pub const Y_AXIS: u16 = 2;
    /// Along z.
    pub const Z_AXIS: u16 = 3;
    /// Translation.
    pub const TRANSLATION: u16 = 4;
    /// Rotation.
    pub const ROTATION: u16 = 5;
}

impl CdrMessage for JointComponentTolerance {
    const MIN_WIRE_SIZE: usize = 31;
    fn description() -> &'static TypeDescription {
        &types::JOINT_COMPONENT_TOLERANCE
    }
    fn write(&self, w: &mut CdrWriter) {
        w.string(&self.joint_name);
        w.u16(self.component);
        w.f64(self.position);
        w.f64(self.velocity);
        w.f64(self.acceleration);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(JointComponentTolerance {
            joint_name: r.string("joint_name")?,
            component: r.u16("component")?,
            position: r.f64("position")?,
            velocity: r.f64("velocity")?,
            acceleration: r.f64("acceleration")?,
        })
    }
}

/// `control_msgs/action/FollowJointTrajectory_Goal`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FollowJointTrajectoryGoal {
    /// The trajectory of the single-DOF joints.
    pub trajectory: JointTrajectory,
    /// The trajectory of multi-DOF joints (servobus has none: a goal
    /// with one is refused).
    pub multi_dof_trajectory: MultiDofJointTrajectory,
    /// Tolerances while moving; broken: `PATH_TOLERANCE_VIOLATED`.
    pub path_tolerance: Vec<JointTolerance>,
    /// Multi-DOF path tolerances.
    pub component_path_tolerance: Vec<JointComponentTolerance>,
    /// Tolerances at the end; broken: `GOAL_TOLERANCE_VIOLATED`.
    pub goal_tolerance: Vec<JointTolerance>,
    /// Multi-DOF goal tolerances.
    pub component_goal_tolerance: Vec<JointComponentTolerance>,
    /// How long after the trajectory's end the goal tolerance may take
    /// to be met.
    pub goal_time_tolerance: RosDuration,
}

impl FollowJointTrajectoryGoal {
    /// Whether the goal asks for anything multi-DOF.
    pub fn has_multi_dof(&self) -> bool {
        !self.multi_dof_trajectory.is_empty()
            || !self.component_path_tolerance.is_empty()
            || !self.component_goal_tolerance.is_empty()
    }
}

impl CdrMessage for FollowJointTrajectoryGoal {
    const MIN_WIRE_SIZE: usize = 66;
    fn description() -> &'static TypeDescription {
        &types::FJT_GOAL
    }
    fn write(&self, w: &mut CdrWriter) {
        self.trajectory.write(w);
        self.multi_dof_trajectory.write(w);
        w.seq(&self.path_tolerance);
        w.seq(&self.component_path_tolerance);
        w.seq(&self.goal_tolerance);
        w.seq(&self.component_goal_tolerance);
        self.goal_time_tolerance.write(w);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(FollowJointTrajectoryGoal {
            trajectory: r.nested("trajectory")?,
            multi_dof_trajectory: r.nested("multi_dof_trajectory")?,
            path_tolerance: r.seq("path_tolerance")?,
            component_path_tolerance: r.seq("component_path_tolerance")?,
            goal_tolerance: r.seq("goal_tolerance")?,
            component_goal_tolerance: r.seq("component_goal_tolerance")?,
            goal_time_tolerance: r.nested("goal_time_tolerance")?,
        })
    }
}

/// `control_msgs/action/FollowJointTrajectory_Result`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct FollowJointTrajectoryResult {
    /// One of the constants below.
    pub error_code: i32,
    /// What went wrong, for a person.
    pub error_string: String,
}

impl FollowJointTrajectoryResult {
    /// The trajectory was followed within its tolerances.
    pub const SUCCESSFUL: i32 = 0;
    /// The goal cannot be run (e.g. a point past a joint limit).
    pub const INVALID_GOAL: i32 = -1;
    /// The goal's joints are not the server's.
    pub const INVALID_JOINTS: i32 = -2;
    /// The trajectory's start is in the past.
    pub const OLD_HEADER_TIMESTAMP: i32 = -3;
    /// A path tolerance was broken while moving.
    pub const PATH_TOLERANCE_VIOLATED: i32 = -4;
    /// A goal tolerance was not met in time.
    pub const GOAL_TOLERANCE_VIOLATED: i32 = -5;
}

impl CdrMessage for FollowJointTrajectoryResult {
    const MIN_WIRE_SIZE: usize = 9;
    fn description() -> &'static TypeDescription {
        &types::FJT_RESULT
    }
    fn write(&self, w: &mut CdrWriter) {
        w.i32(self.error_code);
        w.string(&self.error_string);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(FollowJointTrajectoryResult {
            error_code: r.i32("error_code")?,
            error_string: r.string("error_string")?,
        })
    }
}

/// `control_msgs/action/FollowJointTrajectory_Feedback`: desired, actual
/// and error per joint of `joint_names`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FollowJointTrajectoryFeedback {
    /// When.
    pub header: Header,
    /// The joints, in the order of the points below.
    pub joint_names: Vec<String>,
    /// Where the trajectory is now.
    pub desired: JointTrajectoryPoint,
    /// Where the joints are.
    pub actual: JointTrajectoryPoint,
    /// `desired - actual`.
    pub error: JointTrajectoryPoint,
    /// Multi-DOF joints (none from servobus).
    pub multi_dof_joint_names: Vec<String>,
    /// Multi-DOF desired.
    pub multi_dof_desired: MultiDofJointTrajectoryPoint,
    /// Multi-DOF actual.
    pub multi_dof_actual: MultiDofJointTrajectoryPoint,
    /// Multi-DOF error.
    pub multi_dof_error: MultiDofJointTrajectoryPoint,
}

impl CdrMessage for FollowJointTrajectoryFeedback {
    const MIN_WIRE_SIZE: usize = 153;
    fn description() -> &'static TypeDescription {
        &types::FJT_FEEDBACK
    }
    fn write(&self, w: &mut CdrWriter) {
        self.header.write(w);
        w.string_seq(&self.joint_names);
        self.desired.write(w);
        self.actual.write(w);
        self.error.write(w);
        w.string_seq(&self.multi_dof_joint_names);
        self.multi_dof_desired.write(w);
        self.multi_dof_actual.write(w);
        self.multi_dof_error.write(w);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(FollowJointTrajectoryFeedback {
            header: r.nested("header")?,
            joint_names: r.string_seq("joint_names")?,
            desired: r.nested("desired")?,
            actual: r.nested("actual")?,
            error: r.nested("error")?,
            multi_dof_joint_names: r.string_seq("multi_dof_joint_names")?,
            multi_dof_desired: r.nested("multi_dof_desired")?,
            multi_dof_actual: r.nested("multi_dof_actual")?,
            multi_dof_error: r.nested("multi_dof_error")?,
        })
    }
}

/// `FollowJointTrajectory_SendGoal_Request`: a new goal and its id.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SendGoalRequest {
    /// The id the client chose.
    pub goal_id: Uuid,
    /// The goal.
    pub goal: FollowJointTrajectoryGoal,
}

impl CdrMessage for SendGoalRequest {
    const MIN_WIRE_SIZE: usize = 82;
    fn description() -> &'static TypeDescription {
        &types::FJT_SEND_GOAL_REQUEST
    }
    fn write(&self, w: &mut CdrWriter) {
        self.goal_id.write(w);
        self.goal.write(w);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(SendGoalRequest {
            goal_id: r.nested("goal_id")?,
            goal: r.nested("goal")?,
        })
    }
}

/// `FollowJointTrajectory_SendGoal_Response`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SendGoalResponse {
    /// Whether the goal was accepted.
    pub accepted: bool,
    /// When.
    pub stamp: RosTime,
}

impl CdrMessage for SendGoalResponse {
    const MIN_WIRE_SIZE: usize = 9;
    fn description() -> &'static TypeDescription {
        &types::FJT_SEND_GOAL_RESPONSE
    }
    fn write(&self, w: &mut CdrWriter) {
        w.bool(self.accepted);
        self.stamp.write(w);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(SendGoalResponse {
            accepted: r.bool("accepted")?,
            stamp: r.nested("stamp")?,
        })
    }
}

/// `FollowJointTrajectory_GetResult_Request`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GetResultRequest {
    /// The goal whose result is asked for.
    pub goal_id: Uuid,
}

impl CdrMessage for GetResultRequest {
    const MIN_WIRE_SIZE: usize = 16;
    fn description() -> &'static TypeDescription {
        &types::FJT_GET_RESULT_REQUEST
    }
    fn write(&self, w: &mut CdrWriter) {
        self.goal_id.write(w);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(GetResultRequest {
            goal_id: r.nested("goal_id")?,
        })
    }
}

/// `FollowJointTrajectory_GetResult_Response`: the goal's final status
/// (a [`GoalStatus`](super::action::GoalStatus) value) and its result.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct GetResultResponse {
    /// How the goal ended.
    pub status: i8,
    /// Its result.
    pub result: FollowJointTrajectoryResult,
}

impl CdrMessage for GetResultResponse {
    const MIN_WIRE_SIZE: usize = 10;
    fn description() -> &'static TypeDescription {
        &types::FJT_GET_RESULT_RESPONSE
    }
    fn write(&self, w: &mut CdrWriter) {
        w.i8(self.status);
        self.result.write(w);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(GetResultResponse {
            status: r.i8("status")?,
            result: r.nested("result")?,
        })
    }
}

/// `FollowJointTrajectory_FeedbackMessage`: the `_action/feedback` topic.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FeedbackMessage {
    /// The goal the feedback is about.
    pub goal_id: Uuid,
    /// The feedback.
    pub feedback: FollowJointTrajectoryFeedback,
}

impl CdrMessage for FeedbackMessage {
    const MIN_WIRE_SIZE: usize = 169;
    fn description() -> &'static TypeDescription {
        &types::FJT_FEEDBACK_MESSAGE
    }
    fn write(&self, w: &mut CdrWriter) {
        self.goal_id.write(w);
        self.feedback.write(w);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(FeedbackMessage {
            goal_id: r.nested("goal_id")?,
            feedback: r.nested("feedback")?,
        })
    }
}
