//! The goals of the `follow_joint_trajectory` server and what each control
//! cycle makes of them; no Zenoh here.
//!
//! | event | the goal | result |
//! |---|---|---|
//! | accepted | `EXECUTING` | |
//! | a newer goal accepted | `CANCELED` | `INVALID_GOAL`, "replaced by a newer goal" |
//! | another target, chunk, trajectory or command | `ABORTED` | `INVALID_GOAL`, what took over |
//! | a joint further from its path than its path tolerance (measured, each cycle until the end plus the lead) | `ABORTED`, the joints stop and hold | `PATH_TOLERANCE_VIOLATED`, the joint and the distance |
//! | at the end (plus the lead), every joint within its goal tolerance | `SUCCEEDED` | `SUCCESSFUL` |
//! | not within by `goal_time_tolerance` after the end | `ABORTED` | `GOAL_TOLERANCE_VIOLATED`, the joint and the distance |
//! | canceled | `CANCELING`, the joints stop (jerk limited) and hold; `CANCELED` once still | `SUCCESSFUL`, "canceled" |
//! | the run ends | `ABORTED` | `INVALID_GOAL`, why |
//!
//! Tolerances follow control_msgs: 0 is the server's default, -1 (any
//! negative) no limit. Defaults: no path tolerance; a goal position
//! tolerance of [`DEFAULT_GOAL_POSITION`] rad; no goal velocity
//! tolerance; [`DEFAULT_GOAL_TIME`] s of goal time. Path velocity and all
//! acceleration tolerances are not checked (the servos report no
//! acceleration, and the path's velocity is not in the loop's samples).

use std::collections::VecDeque;

use crate::ros2::{
    CancelGoalRequest, CancelGoalResponse, FollowJointTrajectoryResult as Fjt, GetResultResponse,
    GoalInfo, GoalStatus, GoalStatusArray, JointTolerance, RosTime, Uuid,
};

/// The goal position tolerance when a goal gives 0, rad (1 degree).
pub(super) const DEFAULT_GOAL_POSITION: f64 = 0.017_453_292_519_943_295;

/// The goal time tolerance when a goal gives 0, s.
pub(super) const DEFAULT_GOAL_TIME: f64 = 1.0;

/// How long a canceled goal may take to stop before it counts as
/// canceled anyway, s.
const CANCEL_TIMEOUT: f64 = 3.0;

/// A joint is still when its commanded speed is below this, rad/s.
const STILL: f64 = 1e-3;

/// The goals kept for `get_result` and `status` (the oldest ended first
/// forgotten).
const KEPT: usize = 16;

/// A goal's tolerances for one joint (rad, rad/s); `None`: not checked.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct Tolerance {
    /// Position.
    pub position: Option<f64>,
    /// Velocity.
    pub velocity: Option<f64>,
}

/// A tolerance value as control_msgs means it: 0 the default, negative
/// none.
fn tolerance(value: f64, default: Option<f64>) -> Option<f64> {
    if value > 0.0 {
        Some(value)
    } else if value == 0.0 {
        default
    } else {
        None
    }
}

/// The tolerances `given` for the joints `names`, in their order.
///
/// # Errors
/// A tolerance for a joint the robot does not have (`robot`), with the
/// reason.
pub(super) fn tolerances(
    given: &[JointTolerance],
    names: &[String],
    robot: &[String],
    goal: bool,
) -> Result<Vec<Tolerance>, String> {
    let default = goal.then_some(DEFAULT_GOAL_POSITION);
    let mut out = vec![
        Tolerance {
            position: default,
            velocity: None,
        };
        names.len()
    ];
    for t in given {
        if !robot.contains(&t.name) {
            return Err(format!(
                "a {} tolerance names `{}`, which is not one of the robot's joints",
                if goal { "goal" } else { "path" },
                t.name
            ));
        }
        if let Some(k) = names.iter().position(|n| *n == t.name) {
            out[k] = Tolerance {
                position: tolerance(t.position, default),
                velocity: tolerance(t.velocity, None),
            };
        }
    }
    Ok(out)
}

/// What an accepted goal is checked against.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Track {
    /// The robot's index of each joint of the goal, in its order.
    pub joints: Vec<usize>,
    /// Their names.
    pub names: Vec<String>,
    /// Path tolerances, per joint of the goal.
    pub path: Vec<Tolerance>,
    /// Goal tolerances, per joint of the goal.
    pub goal: Vec<Tolerance>,
    /// How long after the end the goal tolerances may take, s.
    pub goal_time: f64,
    /// Start and end of the trajectory, stream clock (s).
    pub start: f64,
    /// The end.
    pub end: f64,
    /// The last point's positions, per joint of the goal (rad).
    pub last: Vec<f64>,
    /// The node's generation of inputs once the goal's chunk was sent.
    pub generation: u64,
}

/// One goal.
#[derive(Debug, Clone)]
pub(super) struct Goal {
    /// Its id.
    pub id: Uuid,
    /// When it was accepted (or refused).
    pub stamp: RosTime,
    /// Its [`GoalStatus`] value; a refused goal keeps `STATUS_UNKNOWN`.
    pub status: i8,
    /// Its result (a refused goal's says why).
    pub result: Fjt,
    /// What it is checked against; `None` for a refused goal.
    pub track: Option<Track>,
    /// When a cancel was accepted, stream clock (s).
    canceled_at: Option<f64>,
}

impl Goal {
    fn ended(&self) -> bool {
        matches!(
            self.status,
            GoalStatus::STATUS_SUCCEEDED
                | GoalStatus::STATUS_CANCELED
                | GoalStatus::STATUS_ABORTED
                | GoalStatus::STATUS_UNKNOWN
        )
    }

    fn end(&mut self, status: i8, code: i32, why: String) {
        self.status = status;
        self.result = Fjt {
            error_code: code,
            error_string: why,
        };
    }
}

/// One control cycle as the goals see it, rad and rad/s, per joint of the
/// robot.
pub(super) struct Cycle<'a> {
    /// The stream clock's now, s.
    pub now: f64,
    /// The loop's lead, s.
    pub lead: f64,
    /// The generation of inputs (see [`Track::generation`]).
    pub generation: u64,
    /// The path at the time of the reading.
    pub planned: &'a [f64],
    /// The readings.
    pub measured: &'a [Option<f64>],
    /// The measured velocities.
    pub velocity: &'a [f64],
    /// The commanded velocities.
    pub commanded_velocity: &'a [f64],
}

/// What a cycle did to a goal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Change {
    /// It ended (its result can be answered).
    Ended(Uuid),
    /// It ended, and the joints are to stop and hold.
    Stop(Uuid),
}

/// The server's goals, newest last.
#[derive(Debug, Default)]
pub(super) struct Goals {
    list: VecDeque<Goal>,
}

impl Goals {
    fn keep(&mut self, goal: Goal) {
        self.list.retain(|g| g.id != goal.id);
        self.list.push_back(goal);
        while self.list.len() > KEPT {
            match self.list.iter().position(Goal::ended) {
                Some(i) => self.list.remove(i),
                None => self.list.pop_front(),
            };
        }
    }

    /// Records a refused goal: its result says why.
    pub fn refuse(&mut self, id: Uuid, stamp: RosTime, code: i32, why: String) {
        self.keep(Goal {
            id,
            stamp,
            status: GoalStatus::STATUS_UNKNOWN,
            result: Fjt {
                error_code: code,
                error_string: why,
            },
            track: None,
            canceled_at: None,
        });
    }

    /// The running goal gives way to a newer one: returns its id.
    pub fn preempt(&mut self) -> Option<Uuid> {
        let g = self
            .list
            .iter_mut()
            .find(|g| g.status == GoalStatus::STATUS_EXECUTING)?;
        g.end(
            GoalStatus::STATUS_CANCELED,
            Fjt::INVALID_GOAL,
            "replaced by a newer goal".into(),
        );
        Some(g.id)
    }

    /// Records an accepted goal, running.
    pub fn accept(&mut self, id: Uuid, stamp: RosTime, track: Track) {
        self.keep(Goal {
            id,
            stamp,
            status: GoalStatus::STATUS_EXECUTING,
            result: Fjt::default(),
            track: Some(track),
            canceled_at: None,
        });
    }

    /// The running goal, for its feedback.
    pub fn running(&self) -> Option<&Goal> {
        self.list
            .iter()
            .find(|g| g.status == GoalStatus::STATUS_EXECUTING)
    }

    /// The answer to `get_result` for `id`: `None` while it runs.
    pub fn result(&self, id: Uuid) -> Option<GetResultResponse> {
        match self.list.iter().find(|g| g.id == id) {
            Some(g) if !g.ended() => None,
            Some(g) => Some(GetResultResponse {
                status: g.status,
                result: g.result.clone(),
            }),
            None => Some(GetResultResponse {
                status: GoalStatus::STATUS_UNKNOWN,
                result: Fjt {
                    error_code: Fjt::INVALID_GOAL,
                    error_string: "no goal has this id".into(),
                },
            }),
        }
    }

    /// Every goal accepted and still kept, for `_action/status`.
    pub fn status(&self) -> GoalStatusArray {
        GoalStatusArray {
            status_list: self
                .list
                .iter()
                .filter(|g| g.track.is_some())
                .map(|g| GoalStatus {
                    goal_info: GoalInfo {
                        goal_id: g.id,
                        stamp: g.stamp,
                    },
                    status: g.status,
                })
                .collect(),
        }
    }

    /// Takes a cancel request at stream time `now`: the goals it names
    /// that run become `CANCELING`. Returns the response and whether the
    /// joints are to stop.
    pub fn cancel(&mut self, req: &CancelGoalRequest, now: f64) -> (CancelGoalResponse, bool) {
        let info = req.goal_info;
        let all = info.goal_id.is_zero() && info.stamp.is_zero();
        let by_time = |g: &Goal| !info.stamp.is_zero() && g.stamp.as_ns() <= info.stamp.as_ns();
        let mut canceling = Vec::new();
        for g in self.list.iter_mut().filter(|g| g.track.is_some()) {
            let named = all || g.id == info.goal_id || by_time(g);
            if named && g.status == GoalStatus::STATUS_EXECUTING {
                g.status = GoalStatus::STATUS_CANCELING;
                g.canceled_at = Some(now);
                canceling.push(GoalInfo {
                    goal_id: g.id,
                    stamp: g.stamp,
                });
            }
        }
        let known = self
            .list
            .iter()
            .any(|g| g.track.is_some() && g.id == info.goal_id);
        let return_code = if !canceling.is_empty() {
            CancelGoalResponse::ERROR_NONE
        } else if !info.goal_id.is_zero() && !known {
            CancelGoalResponse::ERROR_UNKNOWN_GOAL_ID
        } else if known {
            CancelGoalResponse::ERROR_GOAL_TERMINATED
        } else {
            CancelGoalResponse::ERROR_REJECTED
        };
        let stop = !canceling.is_empty();
        let response = CancelGoalResponse {
            return_code,
            goals_canceling: canceling,
        };
        (response, stop)
    }

    /// Ends every goal not ended yet: `ABORTED`, `why`. Returns their ids.
    pub fn finish(&mut self, why: &str) -> Vec<Uuid> {
        let mut out = Vec::new();
        for g in self.list.iter_mut().filter(|g| !g.ended()) {
            g.end(GoalStatus::STATUS_ABORTED, Fjt::INVALID_GOAL, why.into());
            out.push(g.id);
        }
        out
    }

    /// Checks the goals running or canceling against one cycle.
    pub fn cycle(&mut self, c: &Cycle<'_>, names: &[String]) -> Vec<Change> {
        let mut out = Vec::new();
        for g in self.list.iter_mut() {
            match g.status {
                GoalStatus::STATUS_CANCELING => {
                    let still = c.commanded_velocity.iter().all(|v| v.abs() < STILL);
                    let late = g.canceled_at.is_some_and(|t| c.now - t > CANCEL_TIMEOUT);
                    if still || late {
                        g.end(
                            GoalStatus::STATUS_CANCELED,
                            Fjt::SUCCESSFUL,
                            "canceled: the joints stopped and hold".into(),
                        );
                        out.push(Change::Ended(g.id));
                    }
                }
                GoalStatus::STATUS_EXECUTING => {
                    if let Some(change) = judge(g, c, names) {
                        out.push(change);
                    }
                }
                _ => {}
            }
        }
        out
    }
}

/// One cycle's verdict on a running goal: `None` while it goes on.
fn judge(g: &mut Goal, c: &Cycle<'_>, names: &[String]) -> Option<Change> {
    let t = g.track.as_ref()?;
    if c.generation != t.generation {
        let why = "another target, chunk, trajectory or command took over the joints".into();
        g.end(GoalStatus::STATUS_ABORTED, Fjt::INVALID_GOAL, why);
        return Some(Change::Ended(g.id));
    }
    let done = c.now >= t.end + c.lead;
    let mut worst: Option<(usize, f64)> = None;
    for (k, &j) in t.joints.iter().enumerate() {
        let Some(Some(measured)) = c.measured.get(j) else {
            continue;
        };
        let (reference, tol) = if done {
            (t.last[k], t.goal[k])
        } else {
            (c.planned.get(j).copied().unwrap_or(*measured), t.path[k])
        };
        let off = (reference - measured).abs();
        let speed = c.velocity.get(j).copied().unwrap_or(0.0).abs();
        let over_position = tol.position.is_some_and(|p| off > p);
        let over_speed = done && tol.velocity.is_some_and(|v| speed > v);
        if (over_position || over_speed) && worst.is_none_or(|(_, w)| off > w) {
            worst = Some((k, off));
        }
    }
    let name = |k: usize| names.get(t.joints[k]).cloned().unwrap_or_default();
    match worst {
        Some((k, off)) if !done => {
            let why = format!(
                "joint `{}` was {off:.4} rad from its path at {:.3} s of the trajectory \
                 (path tolerance {:.4} rad)",
                name(k),
                c.now - t.start,
                t.path[k].position.unwrap_or(0.0)
            );
            g.end(
                GoalStatus::STATUS_ABORTED,
                Fjt::PATH_TOLERANCE_VIOLATED,
                why,
            );
            Some(Change::Stop(g.id))
        }
        None if done => {
            g.end(GoalStatus::STATUS_SUCCEEDED, Fjt::SUCCESSFUL, String::new());
            Some(Change::Ended(g.id))
        }
        Some((k, off)) if c.now > t.end + c.lead + t.goal_time => {
            let why = format!(
                "joint `{}` was {off:.4} rad from its goal (goal tolerance {:.4} rad, \
                 velocity {:.4} rad/s) {:.3} s after the trajectory's end",
                name(k),
                t.goal[k].position.unwrap_or(f64::INFINITY),
                c.velocity.get(t.joints[k]).copied().unwrap_or(0.0),
                t.goal_time
            );
            g.end(
                GoalStatus::STATUS_ABORTED,
                Fjt::GOAL_TOLERANCE_VIOLATED,
                why,
            );
            Some(Change::Ended(g.id))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests;
