//! How a run is configured: rate, lag compensation, fault policy, real-time
//! options and channel sizes.

use std::time::Duration;

use servobus_protocol::StatusFlags;

use crate::config::{FaultResponse, JointConfig, Units};
use crate::rt::RtOptions;

/// How far ahead of the planned path the goals are commanded.
///
/// A position servo follows its goal with a lag (its own motion profile, a
/// first-order response, the bus's delay): commanding the path at `t + lead`
/// makes the measured motion land on the planned one.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Lead {
    /// No compensation: the goal of cycle `t` is the path at `t`.
    None,
    /// A fixed lead.
    Fixed(Duration),
    /// Identified while the joints move: the loop runs without lead until
    /// they have moved enough to measure the lag (a least-squares fit of the
    /// tracking error against the planned velocity, corrected for the lead
    /// in force), then ramps the lead in smoothly (0.5 s), and keeps
    /// refining it: every few cycles of motion the estimate is updated from
    /// all readings so far and, when it moved by more than 0.5 ms, the lead
    /// ramps to it. Bounded by `max`.
    Auto {
        /// The largest lead it may choose.
        max: Duration,
    },
}

impl Default for Lead {
    /// [`Lead::Auto`] up to 100 ms.
    fn default() -> Self {
        Lead::Auto {
            max: Duration::from_millis(100),
        }
    }
}

/// What the runtime does when it detects a fault.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Reaction {
    /// Every joint holds where it is measured (where it was last commanded
    /// when no fresh reading exists), from the cycle of detection on.
    Hold,
    /// Every joint stops along a jerk-limited path from its commanded
    /// state (`servobus_trajectory::stop`), then holds.
    Stop,
    /// Torque is disabled on every servo at once (the joints go limp).
    TorqueOff,
}

/// Fault detection thresholds and the reaction to each kind of fault.
///
/// Angles are radians, speeds radians per second (the trajectory's units).
/// Detection counts consecutive cycles in which a joint's reading shows the
/// condition; a fault is raised on the `*_cycles`-th (so a count of 3 means
/// detection within 3 cycles of the condition appearing), and the reaction
/// starts in the cycle of detection.
///
/// This is the run-wide policy. A joint's `faults:` in the robot file
/// ([`JointConfig::faults`]) may hold its stalls or following errors
/// instead (the joint is held pressed, reported as a
/// [`StallEvent`](crate::StallEvent), and the run goes on), ignore them, or
/// give it its own following-error tolerance; every other fault is this
/// policy's for every joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaultPolicy {
    /// Largest tolerated tracking error, rad.
    pub following_error: f64,
    /// Consecutive readings beyond `following_error` that raise the fault.
    pub following_cycles: u32,
    /// Reaction to a following error.
    pub on_following_error: Reaction,
    /// A joint is stalled when its error exceeds this (rad) ...
    pub stall_error: f64,
    /// ... while the path asks at least this speed (rad/s) ...
    pub stall_min_velocity: f64,
    /// ... and the joint moves at less than this fraction of it.
    pub stall_ratio: f64,
    /// Consecutive stalled readings that raise the fault.
    pub stall_cycles: u32,
    /// Reaction to a stalled joint.
    pub on_stall: Reaction,
    /// Consecutive reads without a reply from a servo that raise the fault.
    pub missing_cycles: u32,
    /// Reaction to a missing servo.
    pub on_missing: Reaction,
    /// How long every servo of a bus may be silent at once before the run
    /// stops (with a missing-servo fault naming the bus's silence). One
    /// servo silent while its neighbours answer is missing after
    /// [`missing_cycles`](Self::missing_cycles) reads; the whole bus silent
    /// is the link (a stalled adapter, or a simulator process waiting for
    /// the CPU) or the bus's power, which is judged over time rather than
    /// reads. See [`BUS_SILENCE`].
    pub bus_silence: Duration,
    /// Status bits that are faults (see [`StatusFlags`]); 0 ignores them.
    pub status_mask: u8,
    /// Reaction to a status flag.
    pub on_status: Reaction,
    /// Reaction of the other buses when a port is gone (nothing can be sent
    /// on the bus that lost its port).
    pub on_port_gone: Reaction,
}

/// The default [`FaultPolicy::bus_silence`]: 100 ms. A host that loses the
/// CPU for a while (shared and virtual machines do, for tens of
/// milliseconds under load) delays every reply of a bus at once: through a
/// USB adapter the kernel's hand-off of received bytes waits for the CPU,
/// and a simulator process on a pty waits for it too. Such a stall is not a
/// servo gone. 100 ms is above the longest stalls measured on a loaded
/// 2-core machine (about 40 ms), and short enough that a bus losing its
/// power stops the run before a joint moving at 180 deg/s has gone 20 deg
/// further along its (limit-checked) path.
pub const BUS_SILENCE: Duration = Duration::from_millis(100);

impl Default for FaultPolicy {
    /// 15 degrees of following error for 3 cycles, a stall at 2 degrees of
    /// error with the joint moving at under a quarter of a commanded speed
    /// of at least 5 deg/s for 3 cycles, a servo silent for 3 reads, any
    /// documented status flag; stop on everything but a stall (hold: stop
    /// straining) .
    fn default() -> Self {
        FaultPolicy {
            following_error: 15f64.to_radians(),
            following_cycles: 3,
            on_following_error: Reaction::Stop,
            stall_error: 2f64.to_radians(),
            stall_min_velocity: 5f64.to_radians(),
            stall_ratio: 0.25,
            stall_cycles: 3,
            on_stall: Reaction::Hold,
            missing_cycles: 3,
            on_missing: Reaction::Stop,
            bus_silence: BUS_SILENCE,
            status_mask: StatusFlags::KNOWN,
            on_status: Reaction::Stop,
            on_port_gone: Reaction::Stop,
        }
    }
}

impl FaultPolicy {
    /// A policy that never raises a fault (for benchmarks of the bus alone).
    pub fn disabled() -> Self {
        FaultPolicy {
            following_error: f64::INFINITY,
            stall_error: f64::INFINITY,
            missing_cycles: u32::MAX,
            bus_silence: Duration::MAX,
            status_mask: 0,
            ..FaultPolicy::default()
        }
    }
}

/// One joint's fault policy: the run-wide [`FaultPolicy`] with the joint's
/// own `faults:` of the robot file ([`JointConfig::faults`]). Only a stall
/// and a following error are set per joint; everything else is the run's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct JointPolicy {
    /// A stall of the joint.
    pub stall: FaultResponse,
    /// A following error of the joint.
    pub following: FaultResponse,
    /// The joint's following-error tolerance, rad.
    pub following_error: f64,
}

impl JointPolicy {
    /// `joint`'s policy within `run` (the joint's angles in `units`).
    pub fn new(run: &FaultPolicy, joint: &JointConfig, units: Units) -> Self {
        let f = joint.faults;
        JointPolicy {
            stall: f.stall,
            following: f.following_error,
            following_error: f
                .following_tolerance
                .map_or(run.following_error, |t| units.to_rad(t)),
        }
    }

    /// Whether the joint's stalls are looked for.
    pub fn checks_stall(&self) -> bool {
        self.stall != FaultResponse::Ignore
    }

    /// Whether the joint's following errors are looked for.
    pub fn checks_following(&self) -> bool {
        self.following != FaultResponse::Ignore
    }

    /// Whether a stall holds the joint pressed rather than raising a fault:
    /// with `stall: hold`, or in a live session (`live`) unless ignored.
    pub fn presses_stall(&self, live: bool) -> bool {
        self.stall == FaultResponse::Hold || (live && self.checks_stall())
    }

    /// Whether a following error holds the joint pressed rather than
    /// raising a fault: with `following_error: hold`, or when the joint
    /// does not move towards its path (`blocked`, a stall of a slow path)
    /// and a stall would press it ([`presses_stall`](Self::presses_stall)).
    pub fn presses_following(&self, live: bool, blocked: bool) -> bool {
        self.following == FaultResponse::Hold || (blocked && self.presses_stall(live))
    }
}

/// Everything about a run that is not the robot or the path.
///
/// Build it with struct update syntax from the defaults:
///
/// ```
/// use std::time::Duration;
/// use servobus_runtime::{Lead, RunOptions};
///
/// let options = RunOptions {
///     rate_hz: Some(100.0),
///     lead: Lead::Fixed(Duration::from_millis(20)),
///     ..RunOptions::default()
/// };
/// assert!(options.autoplay);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct RunOptions {
    /// Control rate, Hz (`None`: the robot's `rate`).
    pub rate_hz: Option<f64>,
    /// Lag compensation.
    pub lead: Lead,
    /// Fault thresholds and reactions.
    pub faults: FaultPolicy,
    /// Start playing at once (otherwise hold the start until
    /// [`Command::Play`](crate::Command::Play)).
    pub autoplay: bool,
    /// Before the path, move from wherever the joints are to its start at
    /// this fraction of the joint limits (`None`: the path starts at once,
    /// from wherever the joints are). Skipped when every joint is already
    /// within half a degree of the start.
    pub approach: Option<f64>,
    /// Enable torque on every servo before moving (goals are first set to
    /// the present positions, so nothing jumps).
    pub enable_torque: bool,
    /// Keep commanding the final position this long after the path ends
    /// (tracking goes on, so the report includes the settling).
    pub settle: Duration,
    /// Real-time options of each bus thread (real clock only); with
    /// `core: Some(c)` bus `i` is pinned to core `c + i`.
    pub rt: RtOptions,
    /// Spin instead of sleeping for this long before each deadline (real
    /// clock only).
    pub spin: Duration,
    /// Capacity of the telemetry channel, in messages. A full channel drops
    /// samples (counted in the report), never stalls the loop.
    pub telemetry_capacity: usize,
    /// Capacity of the command channel.
    pub command_capacity: usize,
    /// Units of the angles in the report (`None`: the robot's units).
    pub units: Option<Units>,
    /// How long live targets may fail to come before the joints stop
    /// (jerk limited) and hold; they resume when targets come back.
    pub target_timeout: Duration,
    /// Capacity of the live target channel.
    pub target_capacity: usize,
    /// The grasps a played path makes and ends (a motion's keyframe
    /// `grasp:`), at their times on the path (see [`crate::grasp`]).
    pub grasps: Vec<crate::grasp::GraspAt>,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            rate_hz: None,
            lead: Lead::default(),
            faults: FaultPolicy::default(),
            autoplay: true,
            approach: Some(0.25),
            enable_torque: true,
            settle: Duration::ZERO,
            rt: RtOptions::default(),
            spin: Duration::from_micros(200),
            telemetry_capacity: 4096,
            command_capacity: 16,
            units: None,
            target_timeout: Duration::from_millis(250),
            target_capacity: 64,
            grasps: Vec::new(),
        }
    }
}
