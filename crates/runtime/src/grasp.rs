//! A grasp: a gripper told to close on an object and hold it
//! ([`LiveTarget::with_grasps`](crate::LiveTarget::with_grasps)), with a
//! bounded effort, without ever ending in an overload or overheat
//! shutdown.
//!
//! - **Closing.** The joint's path heads for its `min` (a gripper's closed
//!   end) at [`CLOSING_SPEED_SHARE`] of its `max_velocity`, and the
//!   servo's torque limit (register `torque_limit`, 48, RAM) is set to the
//!   effort asked.
//! - **Contact.** Where the jaws meet the object the joint stalls: its
//!   position stops following the path. Tracking then holds it pressed
//!   there (a [`Telemetry::Stall`](crate::Telemetry::Stall) event), its
//!   goal kept beyond where it stands by a push that follows the servo's
//!   load, read every [`READ_EVERY_S`]: the load is held at
//!   [`HOLD_TARGET`] of the effort, so the servo pushes with about that
//!   and never strains at its torque limit, which its overload protection
//!   counts. Against a soft object the push may become a pull: the goal
//!   backs off until the jaws press no harder than that.
//! - **Holding.** The servo's temperature is read with the load. From
//!   [`WARNING_BELOW_LIMIT_C`] under its temperature limit (its `servo:
//!   max_temperature`, else [`DEFAULT_MAX_TEMPERATURE_C`]) the effort is
//!   lowered by [`LOWER_BY`] (at most every [`LOWER_EVERY_S`], once the
//!   load has settled), down to [`LOWEST_EFFORT`];
//!   at [`LET_GO_BELOW_LIMIT_C`] under it the gripper lets go (its goal
//!   backs off behind where it stands, so the jaws open from the object
//!   and the servo rests and cools) and says so. Each is a
//!   [`Telemetry::Grasp`](crate::Telemetry::Grasp) event.
//! - **In a motion.** A keyframe's `grasp: {gripper: {effort: 40}}` closes
//!   the joint towards its `min` on the way to that keyframe and grasps
//!   from the start of that move ([`GraspAt`]); a later keyframe whose
//!   pose names the joint ends it. A stop or a pause keeps the grip.
//! - **Release.** A position target for the joint ends the grasp: the
//!   torque limit goes back to the joint's (its `servo: torque_limit`, else
//!   the whole torque) and the joint follows its targets again.

use serde::Serialize;

/// The closing speed, as a share of the joint's `max_velocity`.
pub const CLOSING_SPEED_SHARE: f64 = 0.25;

/// How far beyond where it stands a held joint's goal is kept at first:
/// this share of the position error at which its servo would push with
/// the asked effort (a servo's effort is its P gain times its error).
/// From there it follows the servo's load ([`HOLD_TARGET`]).
pub const HOLD_SHARE: f64 = 0.45;

/// The load a held joint's servo is kept at, as a share of the effort
/// asked (its torque limit): under it, so that the servo never strains at
/// its limit, which its overload protection counts.
pub const HOLD_TARGET: f64 = 0.8;

/// How much of the load's shortfall (as a share of the torque) one
/// reading moves the push by, in position errors of the whole torque.
pub const HOLD_GAIN: f64 = 0.5;

/// The P coefficient assumed for a joint whose robot file sets none (the
/// STS3215's factory value).
pub const FACTORY_P: f64 = 32.0;

/// How often a grasping servo's load and temperature are read, s.
pub const READ_EVERY_S: f64 = 0.1;

/// How far under its temperature limit the effort starts to be lowered,
/// degrees C.
pub const WARNING_BELOW_LIMIT_C: f64 = 10.0;

/// How far under its temperature limit the gripper lets go, degrees C.
pub const LET_GO_BELOW_LIMIT_C: f64 = 3.0;

/// The factor the effort is lowered by, at most every [`LOWER_EVERY_S`]
/// while warm.
pub const LOWER_BY: f64 = 0.75;

/// The least time between two lowerings of a warm grasp's effort, s: the
/// load settles at the effort in force first.
pub const LOWER_EVERY_S: f64 = 1.0;

/// The least effort a warm grasp is lowered to, as a share of the torque.
pub const LOWEST_EFFORT: f64 = 0.05;

/// The share of its servo's protection current (register
/// `protection_current`, or the joint's `servo: protection_current`) above
/// which a held grasp's effort is lowered, as when warm.
pub const CURRENT_WARNING_SHARE: f64 = 0.8;

/// The share of its protection current at which a held grasp lets go,
/// when [`CURRENT_READINGS`] readings in a row reach it (one spike does
/// not).
pub const CURRENT_LET_GO_SHARE: f64 = 0.95;

/// How many readings in a row over [`CURRENT_LET_GO_SHARE`] make a grasp
/// let go.
pub const CURRENT_READINGS: u8 = 2;

/// The temperature limit of a joint whose robot file sets none (register
/// `max_temperature` as an STS3215 comes), degrees C.
pub const DEFAULT_MAX_TEMPERATURE_C: f64 = 70.0;

/// The position error (rad) at which a servo of P coefficient `p` pushes
/// with its whole torque: 1600 / P ticks of a 4096-tick turn.
pub fn full_effort_error(p: f64) -> f64 {
    1600.0 / p.max(1.0) * std::f64::consts::TAU / 4096.0
}

/// A grasp a played path makes (`effort`: a share of the servo's torque)
/// or ends (`None`) at `at_s` s on the path: from there the joint grasps
/// as a live target's grasp does, its path (the motion's) closing it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GraspAt {
    /// The time on the path, s.
    pub at_s: f64,
    /// The joint, in the robot's joint order.
    pub joint: usize,
    /// The effort, 0..=1 of the torque; `None` ends the grasp.
    pub effort: Option<f64>,
}

/// The efforts of `schedule` (sorted by time) at path time `t` into `out`
/// (robot order): per joint, its latest entry at or before `t`.
pub(crate) fn efforts_at(schedule: &[GraspAt], t: f64, out: &mut [Option<f64>]) {
    for g in schedule.iter().take_while(|g| g.at_s <= t) {
        if let Some(o) = out.get_mut(g.joint) {
            *o = g.effort;
        }
    }
}

/// What happened to a grasp.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "event")]
#[non_exhaustive]
pub enum GraspEvent {
    /// The joint began to close, its torque limit set to `effort_pct`.
    Closing {
        /// The effort asked, percent of the servo's torque.
        effort_pct: f64,
    },
    /// Warm, or drawing much current: the effort was lowered.
    Lowered {
        /// The effort now, percent.
        effort_pct: f64,
        /// The temperature read, degrees C.
        temperature_c: f64,
        /// The current read, mA (`None`: the series has no current
        /// register).
        current_ma: Option<f64>,
        /// Which of them lowered it.
        cause: GraspCause,
    },
    /// Near its temperature limit, or at its protection current: the
    /// gripper let go (backed off from the object).
    LetGo {
        /// The temperature read, degrees C.
        temperature_c: f64,
        /// The current read, mA (`None`: the series has no current
        /// register).
        current_ma: Option<f64>,
        /// Which of them made it let go.
        cause: GraspCause,
    },
    /// A position target ended the grasp; the torque limit is the
    /// joint's again.
    Released,
}

/// What lowered a grasp's effort, or made it let go.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GraspCause {
    /// The servo's temperature, near its limit.
    Temperature,
    /// The servo's current, near its protection current.
    Current,
}

/// A grasp event of one joint, at a cycle's time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GraspReport {
    /// The joint, in the robot's joint order.
    pub joint: usize,
    /// The cycle's time since the start of the run, s.
    pub time_s: f64,
    /// What happened.
    #[serde(flatten)]
    pub event: GraspEvent,
}
