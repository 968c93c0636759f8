//! What every ROS 2 action shares (`action_msgs`, `unique_identifier_msgs`):
//! goal ids, goal statuses for the `_action/status` topic and the
//! `_action/cancel_goal` service.
//!
//! | status | value | meaning |
//! |---|---|---|
//! | [`GoalStatus::STATUS_UNKNOWN`] | 0 | not known (e.g. no such goal) |
//! | [`GoalStatus::STATUS_ACCEPTED`] | 1 | accepted, waiting to run |
//! | [`GoalStatus::STATUS_EXECUTING`] | 2 | running |
//! | [`GoalStatus::STATUS_CANCELING`] | 3 | cancel accepted, stopping |
//! | [`GoalStatus::STATUS_SUCCEEDED`] | 4 | done, succeeded |
//! | [`GoalStatus::STATUS_CANCELED`] | 5 | done, canceled |
//! | [`GoalStatus::STATUS_ABORTED`] | 6 | done, aborted by the server |

use super::cdr::{CdrError, CdrMessage, CdrReader, CdrWriter};
use super::hash::TypeDescription;
use super::msgs::RosTime;
use super::types;

/// `unique_identifier_msgs/msg/UUID`: a goal's id, chosen by the client.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Uuid(pub [u8; 16]);

impl Uuid {
    /// Whether all 16 bytes are zero: in a cancel request, "every goal".
    pub fn is_zero(&self) -> bool {
        self.0 == [0; 16]
    }
}

impl CdrMessage for Uuid {
    const MIN_WIRE_SIZE: usize = 16;
    fn description() -> &'static TypeDescription {
        &types::UUID
    }
    fn write(&self, w: &mut CdrWriter) {
        w.bytes(&self.0);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Uuid(r.bytes16("uuid")?))
    }
}

/// `action_msgs/msg/GoalInfo`: a goal's id and when it was accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GoalInfo {
    /// The goal's id.
    pub goal_id: Uuid,
    /// When the server accepted it.
    pub stamp: RosTime,
}

impl CdrMessage for GoalInfo {
    const MIN_WIRE_SIZE: usize = 24;
    fn description() -> &'static TypeDescription {
        &types::GOAL_INFO
    }
    fn write(&self, w: &mut CdrWriter) {
        self.goal_id.write(w);
        self.stamp.write(w);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(GoalInfo {
            goal_id: r.nested("goal_id")?,
            stamp: r.nested("stamp")?,
        })
    }
}

/// `action_msgs/msg/GoalStatus`: one goal and where it is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GoalStatus {
    /// The goal.
    pub goal_info: GoalInfo,
    /// One of the `STATUS_` values.
    pub status: i8,
}

impl GoalStatus {
    /// Not known.
    pub const STATUS_UNKNOWN: i8 = 0;
    /// Accepted, waiting to run.
    pub const STATUS_ACCEPTED: i8 = 1;
    /// Running.
    pub const STATUS_EXECUTING: i8 = 2;
    /// A cancel was accepted; stopping.
    pub const STATUS_CANCELING: i8 = 3;
    /// Done: succeeded.
    pub const STATUS_SUCCEEDED: i8 = 4;
    /// Done: canceled.
    pub const STATUS_CANCELED: i8 = 5;
    /// Done: aborted by the server.
    pub const STATUS_ABORTED: i8 = 6;
}

impl CdrMessage for GoalStatus {
    const MIN_WIRE_SIZE: usize = 25;
    fn description() -> &'static TypeDescription {
        &types::GOAL_STATUS
    }
    fn write(&self, w: &mut CdrWriter) {
        self.goal_info.write(w);
        w.i8(self.status);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(GoalStatus {
            goal_info: r.nested("goal_info")?,
            status: r.i8("status")?,
        })
    }
}

/// `action_msgs/msg/GoalStatusArray`: the `_action/status` topic, every
/// goal the server knows of.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct GoalStatusArray {
    /// The goals.
    pub status_list: Vec<GoalStatus>,
}

impl CdrMessage for GoalStatusArray {
    const MIN_WIRE_SIZE: usize = 4;
    fn description() -> &'static TypeDescription {
        &types::GOAL_STATUS_ARRAY
    }
    fn write(&self, w: &mut CdrWriter) {
        w.seq(&self.status_list);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(GoalStatusArray {
            status_list: r.seq("status_list")?,
        })
    }
}

/// `action_msgs/srv/CancelGoal_Request`. Which goals it cancels:
///
/// | goal id | stamp | goals |
/// |---|---|---|
/// | zero | zero | all |
/// | zero | t | all accepted at or before t |
/// | id | zero | that goal |
/// | id | t | that goal and all accepted at or before t |
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CancelGoalRequest {
    /// Which goals.
    pub goal_info: GoalInfo,
}

impl CdrMessage for CancelGoalRequest {
    const MIN_WIRE_SIZE: usize = 24;
    fn description() -> &'static TypeDescription {
        &types::CANCEL_GOAL_REQUEST
    }
    fn write(&self, w: &mut CdrWriter) {
        self.goal_info.write(w);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(CancelGoalRequest {
            goal_info: r.nested("goal_info")?,
        })
    }
}

/// `action_msgs/srv/CancelGoal_Response`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct CancelGoalResponse {
    /// One of the `ERROR_` values.
    pub return_code: i8,
    /// The goals that are now being canceled.
    pub goals_canceling: Vec<GoalInfo>,
}

impl CancelGoalResponse {
    /// The request was taken (some goals may be canceling).
    pub const ERROR_NONE: i8 = 0;
    /// The request was refused.
    pub const ERROR_REJECTED: i8 = 1;
    /// No goal has the id asked for.
    pub const ERROR_UNKNOWN_GOAL_ID: i8 = 2;
    /// The goal has already ended.
    pub const ERROR_GOAL_TERMINATED: i8 = 3;
}

impl CdrMessage for CancelGoalResponse {
    const MIN_WIRE_SIZE: usize = 5;
    fn description() -> &'static TypeDescription {
        &types::CANCEL_GOAL_RESPONSE
    }
    fn write(&self, w: &mut CdrWriter) {
        w.i8(self.return_code);
        w.seq(&self.goals_canceling);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(CancelGoalResponse {
            return_code: r.i8("return_code")?,
            goals_canceling: r.seq("goals_canceling")?,
        })
    }
}
