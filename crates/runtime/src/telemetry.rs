//! What the loop publishes every cycle.
//!
//! Messages are plain `Copy` data of fixed size, sent with `try_send` on a
//! bounded channel: publishing never allocates and never blocks; when the
//! consumer is slow the sample is dropped and counted
//! ([`Report::telemetry_dropped`](crate::Report::telemetry_dropped)).

use std::time::Duration;

use serde::Serialize;
use servobus_protocol::StatusFlags;

use crate::fault::Fault;
pub use crate::live::LiveEvent;

/// Most joints one [`CycleSample`] carries; a bus with more joints sends
/// several samples per cycle, each with the next joints.
pub const SAMPLE_JOINTS: usize = 24;

/// One joint in one cycle. Angles are in the report's units
/// ([`RunOptions::units`](crate::RunOptions::units)).
///
/// A wheel joint (`mode: wheel`) has no position to follow, and its sample
/// is of speeds, units/s: `commanded` is its commanded speed (ramped
/// within its acceleration limit), `planned` the speed it heads for,
/// `measured` and `velocity` its present speed, `error` commanded -
/// measured; it is never `clamped` or `stalled`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct JointSample {
    /// Index of the joint in the robot's joint order.
    pub joint: usize,
    /// The goal sent this cycle (the path at `t + lead`, clamped); a
    /// wheel's commanded speed, units/s.
    pub commanded: f64,
    /// The path at the time of the reading (what the joint should be at);
    /// the speed a wheel heads for, units/s.
    pub planned: f64,
    /// The last reading, if any; a wheel's present speed, units/s.
    pub measured: Option<f64>,
    /// `planned - measured` at the last fresh reading (0 when none); a
    /// wheel's commanded - measured speed, units/s.
    pub error: f64,
    /// Measured velocity, units/s (a wheel's present speed).
    pub velocity: f64,
    /// Time since the last reading of this joint.
    pub feedback_age: Duration,
    /// When the last reading was taken (the servo had heard the request it
    /// answered), on the bus's clock: the clock of the run's buses, whose
    /// epoch a program that stamps its targets on the same clock shares.
    /// Zero before the first reading.
    pub measured_at: Duration,
    /// Whether the reading is older than two of its read periods.
    pub stale: bool,
    /// Whether the goal was clamped to the joint's limits this cycle.
    pub clamped: bool,
    /// The status flags of the servo's last reply.
    pub flags: StatusFlags,
    /// Reads in a row the servo has not answered (0 once it answers).
    pub missing_reads: u32,
    /// Held pressed against a stop (live sessions): this cycle's goal was
    /// kept within `STALL_PUSH` (1 degree) of where it stands.
    pub stalled: bool,
}

/// A joint of a live session stalled and is held pressed with bounded
/// effort, or was let go to follow again (see `STALL_PUSH`, 1 degree).
/// Angles are in the report's units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StallEvent {
    /// Index of the joint in the robot's joint order.
    pub joint: usize,
    /// Index of its bus in the robot's bus order.
    pub bus: usize,
    /// Its servo's ID.
    pub servo_id: u8,
    /// True: it stalled and is held; false: its path came back within the
    /// bound and it follows again.
    pub held: bool,
    /// The cycle's time since the start of the run, s.
    pub time_s: f64,
    /// The cycle.
    pub cycle: u64,
    /// Where it was measured.
    pub position: f64,
    /// The goal's largest distance beyond that while held, signed in the
    /// direction pushed.
    pub push: f64,
}

/// One bus's cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CycleSample {
    /// Index of the bus in the robot's bus order.
    pub bus: usize,
    /// Cycle number (cycle `k` is due at `k` periods after the start).
    pub cycle: u64,
    /// The cycle's deadline: time since the start of the run, s.
    pub time_s: f64,
    /// How late the cycle started after its deadline.
    pub lateness: Duration,
    /// How long the cycle's bus work took (write, read, tracking).
    pub busy: Duration,
    /// Deadlines skipped before this cycle because the previous overran.
    pub skipped: u64,
    /// The current lead (lag compensation).
    pub lead: Duration,
    len: usize,
    joints: [JointSample; SAMPLE_JOINTS],
}

impl CycleSample {
    pub(crate) fn new(bus: usize, cycle: u64, time_s: f64) -> Self {
        CycleSample {
            bus,
            cycle,
            time_s,
            lateness: Duration::ZERO,
            busy: Duration::ZERO,
            skipped: 0,
            lead: Duration::ZERO,
            len: 0,
            joints: [JointSample::default(); SAMPLE_JOINTS],
        }
    }

    /// Adds a joint; false when full.
    pub(crate) fn push(&mut self, joint: JointSample) -> bool {
        match self.joints.get_mut(self.len) {
            Some(slot) => {
                *slot = joint;
                self.len += 1;
                true
            }
            None => false,
        }
    }

    pub(crate) fn clear_joints(&mut self) {
        self.len = 0;
    }

    /// The joints in this sample.
    pub fn joints(&self) -> &[JointSample] {
        &self.joints[..self.len]
    }
}

/// Why a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Finish {
    /// The path (and the settling time) played to its end.
    Completed,
    /// A [`Command::Stop`](crate::Command::Stop) stopped it.
    Stopped,
    /// A [`Command::TorqueOff`](crate::Command::TorqueOff) ended it.
    TorqueOff,
    /// A fault ended it after its reaction.
    Fault,
    /// Every command sender was dropped while the run waited for
    /// [`Command::Play`](crate::Command::Play).
    Abandoned,
}

/// Why a command ([`Command`](crate::Command)) was not carried out.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Rejection {
    /// A replacing path ([`Command::Replace`](crate::Command::Replace)) for
    /// another number of joints than the robot has.
    #[error("the new path has {given} joints, the robot {expected}")]
    NewPathJoints {
        /// The robot's joints.
        expected: usize,
        /// The new path's.
        given: usize,
    },
    /// The transition the command asks for (a stop, a replacement) cannot
    /// be planned.
    #[error("cannot plan the {what}: {source}")]
    Trajectory {
        /// Which transition.
        what: &'static str,
        /// The planner's reason.
        source: servobus_trajectory::PlanError,
    },
    /// Another failure of the run, as its message (no command fails so
    /// today: this keeps a future one from being lost).
    #[error("{0}")]
    Other(String),
}

impl From<crate::RunError> for Rejection {
    fn from(error: crate::RunError) -> Self {
        match error {
            crate::RunError::NewPathJoints { expected, given } => {
                Rejection::NewPathJoints { expected, given }
            }
            crate::RunError::Trajectory { what, source } => Rejection::Trajectory { what, source },
            other => Rejection::Other(other.to_string()),
        }
    }
}

/// A telemetry message.
// The cycle sample is the message sent every cycle and is kept inline on
// purpose: boxing it would allocate in the loop.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Telemetry {
    /// One bus's cycle (or part of it, for buses of more than
    /// [`SAMPLE_JOINTS`] joints).
    Cycle(CycleSample),
    /// A fault was detected; its reaction has started.
    Fault(Fault),
    /// A joint of a live session stalled (a gripper on its end stop or on
    /// an object): the run goes on with the joint held pressed, or it was
    /// let go (`StallEvent::held`).
    Stall(StallEvent),
    /// A grasp began, was lowered for heat, let go, or was released (see
    /// [`crate::grasp`]).
    Grasp(crate::grasp::GraspReport),
    /// A command could not be carried out (a replacement path with the
    /// wrong joints, say); the run goes on as before.
    Rejected(Rejection),
    /// The live following stopped for lack of targets, or resumed.
    Live {
        /// What happened.
        event: LiveEvent,
        /// When: the cycle's time since the start of the run, s.
        time_s: f64,
    },
    /// The run ended; the report follows from
    /// [`Runner::join`](crate::Runner::join) or
    /// [`VirtualRun::report`](crate::VirtualRun::report).
    Finished(Finish),
}
