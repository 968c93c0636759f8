//! Tracking: each joint's readings against the path, and the faults they
//! show (a silent servo, a status flag, a stall, a following error).
//!
//! Detection counts consecutive cycles in which a joint shows the condition
//! and raises the fault on the policy's count, so that one bad reading does
//! not stop a robot and a real fault is found within a few cycles.
//!
//! In a live session (a run following live targets, see
//! [`Tracker::live_session`]) a joint that stalls is pressed against
//! something (a gripper on its end stop or on what it holds), which is not
//! a fault: instead of raising one, tracking marks the joint [`Press`]ed and
//! the goal writer keeps its goal within [`STALL_PUSH`] of where it stands
//! (see `goals`), until its commanded goal comes back within that bound.
//! A following error of a joint that does not move towards its path is
//! taken the same way. A joint whose robot file says `faults: {stall: hold}`
//! (or `following_error: hold`) is pressed so in any run, played or live;
//! `ignore` skips the check for it ([`JointPolicy`]). Status flags (heat,
//! over-current, overload) and a missing servo still raise their faults,
//! pressed or not.
//!
//! A wheel joint has no position to follow: it is not judged against the
//! path (no following error, stall or press). Its reading is its present
//! speed (rad/s, through the joint's mapping); its status flags and its
//! silence raise their faults as any joint's do.

use std::time::Duration;

use servobus_driver::MissingReason;
use servobus_protocol::StatusFlags;
use servobus_trajectory::JointState;

use crate::config::{BusConfig, JointMap, Units};
use crate::fault::{FaultKind, STALL_PUSH};
use crate::options::{FaultPolicy, JointPolicy, Reaction};
use crate::stats::RunningError;

/// One reading of a joint's position, as it came off the bus. (How late
/// replies are is learned per bus, in `busloop::link`.)
#[derive(Debug, Clone, Copy)]
pub(crate) struct Reading {
    /// The position, ticks.
    pub ticks: i32,
    /// The present speed, steps/s, when read (buses with wheels).
    pub speed: Option<i32>,
    /// When it was read, on the bus's clock.
    pub at: Duration,
    /// The status flags of the reply.
    pub flags: StatusFlags,
}

/// The tracking state of one joint.
#[derive(Debug)]
pub(crate) struct JointTrack {
    /// Index in the robot's joint order.
    pub robot_index: usize,
    pub name: String,
    pub id: u8,
    map: JointMap,
    pub measured: Option<f64>,
    pub measured_at: Duration,
    prev: Option<(f64, Duration)>,
    /// Measured velocity, rad/s (a wheel's: its present speed).
    pub velocity: f64,
    /// A wheel joint: tracked by its speed, not against the path.
    pub wheel: bool,
    /// Its own stall and following-error policy.
    policy: JointPolicy,
    /// Steps/s of the speed register per rad/s of joint speed (signed by
    /// the joint's direction).
    steps_per_rad: f64,
    /// A wheel's present speed at its last reading, rad/s.
    pub speed: Option<f64>,
    /// The largest |present speed| read, rad/s.
    pub peak_speed: f64,
    /// The path at the time of the reading, rad and rad/s.
    pub planned: f64,
    planned_velocity: f64,
    /// `planned - measured` at the last fresh reading.
    pub error: f64,
    /// Read in this cycle.
    fresh: bool,
    /// Status flags of its last reply.
    pub flags: StatusFlags,
    /// Why the last read of it failed.
    why_missing: Option<MissingReason>,
    pub err: RunningError,
    follow: u32,
    stall: u32,
    /// Reads in a row it has not answered.
    pub missing: u32,
    /// Pressed against a stop (live sessions only): held with bounded
    /// effort instead of raising a stall fault.
    pub press: Option<Press>,
    /// Grasping (see [`crate::grasp`]): a stall presses the joint in any
    /// run, its goal kept this far (rad) beyond where it stands.
    pub grasp_push: Option<f64>,
    /// The press began at this cycle's reading (to be published).
    pub press_began: bool,
    /// Presses so far.
    pub presses: u64,
    /// Cycles it has been held pressed.
    pub pressed_cycles: u64,
    /// This cycle's goal was kept within its press's bound.
    pub held: bool,
}

/// A joint pressed against a stop or an object: its goal is kept within
/// `push` ([`STALL_PUSH`], or a grasp's) beyond `anchor` in the direction
/// `dir`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Press {
    /// The direction the path pushes: +1 (towards higher angles) or -1.
    pub dir: f64,
    /// How far beyond the anchor the goal may go, rad.
    pub push: f64,
    /// The furthest position measured in that direction since the press
    /// began, rad (at a stop: where the joint stands). The goal is bounded
    /// from there rather than from each reading, so that a joint pushed
    /// back (a raised arm sagging under its load) is not let go further.
    pub anchor: f64,
}

impl Press {
    /// The furthest goal (rad) the press allows in its direction.
    pub fn bound(&self) -> f64 {
        self.anchor + self.dir * self.push
    }

    /// `goal` kept within the bound, in the direction pushed only.
    pub fn limit(&self, goal: f64) -> f64 {
        let b = self.bound();
        if (goal - b) * self.dir > 0.0 {
            b
        } else {
            goal
        }
    }

    /// Whether `goal` (the path's) no longer goes beyond the bound: the
    /// target has moved back from the stop, or the joint has caught up.
    pub fn released_by(&self, goal: f64) -> bool {
        (goal - self.bound()) * self.dir <= 0.0
    }
}

impl JointTrack {
    fn observe(&mut self, r: Reading) {
        let p = self.map.from_ticks(r.ticks);
        if let Some((q, t)) = self.prev {
            if r.at > t {
                self.velocity = (p - q) / (r.at - t).as_secs_f64();
            }
        }
        if let Some(steps) = r.speed.filter(|_| self.wheel && self.steps_per_rad != 0.0) {
            let v = f64::from(steps) / self.steps_per_rad;
            self.speed = Some(v);
            self.velocity = v;
            self.peak_speed = self.peak_speed.max(v.abs());
        }
        self.prev = Some((p, r.at));
        self.measured = Some(p);
        self.measured_at = r.at;
        self.flags = r.flags;
        self.fresh = true;
        self.missing = 0;
    }

    /// Where the joint should hold: its fresh reading, else `goal`.
    fn hold_position(&self, stale: bool, goal: f64) -> f64 {
        match self.measured {
            Some(p) if !stale => self.map.clamp(p).value,
            _ => goal,
        }
    }
}

/// A fault tracking found: the joint (index in the bus), what, and the
/// policy's reaction to it.
#[derive(Debug)]
pub(crate) struct Found {
    pub joint: Option<usize>,
    pub kind: FaultKind,
    pub reaction: Reaction,
}

/// The tracking of one bus's joints.
#[derive(Debug)]
pub(crate) struct Tracker {
    pub joints: Vec<JointTrack>,
    policy: FaultPolicy,
    /// The report's units, for the values of a fault.
    units: Units,
    /// A reading older than this is stale (two of its read periods).
    pub stale_after: Duration,
    /// Servo readings missing after every retry.
    pub missed: u64,
    /// Reads in a row in which no servo of the bus answered ...
    silent_reads: u32,
    /// ... and how long since one did, at the last of them.
    silent_for: Duration,
    /// The run follows live targets: a stalled joint is pressed, not a fault.
    live: bool,
}

impl Tracker {
    /// `config`'s joints, whose first is robot joint `first_joint`.
    pub fn new(
        config: &BusConfig,
        first_joint: usize,
        units: Units,
        report_units: Units,
        policy: FaultPolicy,
        stale_after: Duration,
    ) -> Self {
        let joints = config
            .joints
            .iter()
            .enumerate()
            .map(|(i, j)| {
                let map = JointMap::new(j, units);
                JointTrack {
                    robot_index: first_joint + i,
                    name: j.name.clone(),
                    id: j.id,
                    map,
                    measured: None,
                    measured_at: Duration::ZERO,
                    prev: None,
                    velocity: 0.0,
                    wheel: j.is_wheel(),
                    policy: JointPolicy::new(&policy, j, units),
                    steps_per_rad: map.raw_ticks(1.0) - map.raw_ticks(0.0),
                    speed: None,
                    peak_speed: 0.0,
                    planned: 0.0,
                    planned_velocity: 0.0,
                    error: 0.0,
                    fresh: false,
                    flags: StatusFlags(0),
                    why_missing: None,
                    err: RunningError::default(),
                    follow: 0,
                    stall: 0,
                    missing: 0,
                    press: None,
                    grasp_push: None,
                    press_began: false,
                    presses: 0,
                    pressed_cycles: 0,
                    held: false,
                }
            })
            .collect();
        Tracker {
            joints,
            policy,
            units: report_units,
            stale_after,
            missed: 0,
            silent_reads: 0,
            silent_for: Duration::ZERO,
            live: false,
        }
    }

    /// From now on the run is a live session: a joint that stalls is held
    /// pressed with bounded effort instead of raising a stall fault.
    pub fn live_session(&mut self) {
        self.live = true;
    }

    /// Joint `i` (of the bus) grasps, a stall pressing it `push` rad
    /// beyond where it stands (`None`: it grasps no more; a press it is in
    /// keeps its push until it is let go).
    pub fn set_grasp(&mut self, i: usize, push: Option<f64>) {
        if let Some(j) = self.joints.get_mut(i) {
            j.grasp_push = push;
            if let (Some(press), Some(push)) = (&mut j.press, push) {
                press.push = push;
            }
        }
    }

    /// A new cycle: no reading is fresh yet.
    pub fn begin(&mut self) {
        for j in &mut self.joints {
            j.fresh = false;
        }
    }

    /// Joint `i` (of the bus) was read.
    pub fn observe(&mut self, i: usize, reading: Reading) {
        if let Some(j) = self.joints.get_mut(i) {
            j.observe(reading);
            self.silent_reads = 0;
        }
    }

    /// No servo of the bus (two or more, all asked) answered a read that
    /// ended at `at`: the bus itself is silent. The joints' own counts do not move;
    /// [`track`](Self::track) judges the silence by its length instead.
    pub fn bus_silent(&mut self, at: Duration) {
        self.missed += self.joints.len() as u64;
        self.silent_reads += 1;
        let last_answer = self.joints.iter().map(|j| j.measured_at).max();
        self.silent_for = at.saturating_sub(last_answer.unwrap_or_default());
    }

    /// Joint `i` was asked and gave no usable reading (`None`: it answered
    /// with an impossible position).
    pub fn miss(&mut self, i: usize, why: Option<MissingReason>) {
        if let Some(j) = self.joints.get_mut(i) {
            j.missing += 1;
            if why.is_some() {
                j.why_missing = why;
            }
            self.missed += 1;
        }
    }

    /// Forgets the start-up readings' motion, so that the first cycle's
    /// velocity is not measured across the start-up.
    pub fn settle(&mut self) {
        for j in &mut self.joints {
            j.prev = None;
            j.fresh = false;
        }
    }

    /// Where each joint stands (its fresh reading, else `goal(i)`), into
    /// `out` (robot order), at time `now`.
    pub fn hold_positions(&self, now: Duration, goal: impl Fn(usize) -> f64, out: &mut [f64]) {
        for (i, j) in self.joints.iter().enumerate() {
            if let Some(slot) = out.get_mut(j.robot_index) {
                let stale = now.saturating_sub(j.measured_at) > self.stale_after;
                *slot = j.hold_position(stale, goal(i));
            }
        }
    }

    /// When the earliest of this cycle's fresh readings was taken.
    pub fn first_fresh(&self) -> Option<Duration> {
        self.joints
            .iter()
            .filter(|j| j.fresh)
            .map(|j| j.measured_at)
            .min()
    }

    /// `(error, planned velocity)` of every joint read this cycle and free
    /// to follow its path (a pressed joint's error is the stop's, not its
    /// lag).
    pub fn fresh_errors(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.joints
            .iter()
            .filter(|j| j.fresh && !j.wheel && j.measured.is_some() && j.press.is_none())
            .map(|j| (j.error, j.planned_velocity))
    }

    /// Updates every joint's error against `reference` (robot order, the
    /// path at `reference_at`, on the bus's clock) and returns the first
    /// fault found. A joint read at another time (a re-ask later in the
    /// cycle) is judged against the path at its own reading's time, to
    /// first order: the reference moved on at its velocity.
    pub fn track(&mut self, reference: &[JointState], reference_at: Duration) -> Option<Found> {
        let p = self.policy;
        let u = self.units;
        let mut found: Option<Found> = None;
        if self.silent_reads >= p.missing_cycles && self.silent_for >= p.bus_silence {
            let ms = self.silent_for.as_millis();
            found = Some(Found {
                joint: None,
                kind: FaultKind::Missing {
                    cycles: self.silent_reads,
                    reason: format!(
                        "no servo of the bus answered for {ms} ms: the link or the bus's power, not one servo"
                    ),
                },
                reaction: p.on_missing,
            });
        }
        for (i, j) in self.joints.iter_mut().enumerate() {
            let mut r = reference.get(j.robot_index).copied().unwrap_or_default();
            if j.fresh {
                let dt = j.measured_at.as_secs_f64() - reference_at.as_secs_f64();
                r.position += r.velocity * dt;
            }
            j.planned = r.position;
            j.planned_velocity = r.velocity;
            if j.missing > 0 && j.missing >= p.missing_cycles && found.is_none() {
                let reason = j
                    .why_missing
                    .map_or_else(|| "unreadable reply".to_owned(), |r| r.to_string());
                let kind = FaultKind::Missing {
                    cycles: j.missing,
                    reason,
                };
                found = Some(Found {
                    joint: Some(i),
                    kind,
                    reaction: p.on_missing,
                });
            }
            if !j.fresh {
                continue;
            }
            if j.wheel {
                // No path to follow: only its status flags are judged.
                if found.is_none() {
                    found = flag_fault(j, &p).map(|(kind, reaction)| Found {
                        joint: Some(i),
                        kind,
                        reaction,
                    });
                }
                continue;
            }
            let Some(m) = j.measured else { continue };
            let e = r.position - m;
            j.error = e;
            j.err.record(e);
            let kind = judge(j, &p, e, r.velocity, u, self.live);
            if found.is_none() {
                found = kind.map(|(kind, reaction)| Found {
                    joint: Some(i),
                    kind,
                    reaction,
                });
            }
        }
        found
    }
}

/// The fault `j`'s status flags show, if any (those of the policy's mask).
fn flag_fault(j: &JointTrack, p: &FaultPolicy) -> Option<(FaultKind, Reaction)> {
    let flags = j.flags.bits() & p.status_mask;
    (flags != 0).then(|| {
        let names = StatusFlags(flags).to_string();
        (FaultKind::Status { flags, names }, p.on_status)
    })
}

/// Counts `j`'s stalled and off-path readings (error `e` against a path
/// moving at `v`) and names the first fault they or its status flags show.
/// A stall, or a following error, that the joint's policy holds (`hold`,
/// or a live session: `live`) presses the joint instead (see [`Press`]).
fn judge(
    j: &mut JointTrack,
    p: &FaultPolicy,
    e: f64,
    v: f64,
    u: Units,
    live: bool,
) -> Option<(FaultKind, Reaction)> {
    let jp = j.policy;
    let stalled = jp.checks_stall()
        && e.abs() > p.stall_error
        && v.abs() >= p.stall_min_velocity
        && (j.velocity.abs() < p.stall_ratio * v.abs() || j.velocity.signum() != v.signum());
    j.stall = if stalled { j.stall + 1 } else { 0 };
    j.follow = if jp.checks_following() && e.abs() > jp.following_error {
        j.follow + 1
    } else {
        0
    };
    if let Some(fault) = flag_fault(j, p) {
        return Some(fault);
    }
    let measured = j.measured.unwrap_or(j.planned);
    if let Some(press) = &mut j.press {
        // Held: the error is the stop's, not a fault. A joint that gets
        // further (what it pressed on gave way) moves the anchor on.
        if (measured - press.anchor) * press.dir > 0.0 {
            press.anchor = measured;
        }
        j.stall = 0;
        j.follow = 0;
        return None;
    }
    // Not moving towards its path at a quarter of the slowest speed a
    // stall is judged at: blocked, however slowly the path goes.
    let towards = j.velocity * e.signum();
    let blocked = towards < p.stall_ratio * p.stall_min_velocity;
    let stall_held = j.stall >= p.stall_cycles && jp.presses_stall(live);
    let follow_held = j.follow >= p.following_cycles && jp.presses_following(live, blocked);
    let grasp_held = j.grasp_push.is_some()
        && (j.stall >= p.stall_cycles || (j.follow >= p.following_cycles && blocked));
    if stall_held || follow_held || grasp_held {
        j.press = Some(Press {
            dir: e.signum(),
            push: j.grasp_push.unwrap_or(STALL_PUSH),
            anchor: measured,
        });
        j.press_began = true;
        j.presses += 1;
        j.stall = 0;
        j.follow = 0;
        return None;
    }
    if j.stall >= p.stall_cycles {
        let kind = FaultKind::Stall {
            error: u.from_rad(e),
            planned_velocity: u.from_rad(v),
            measured_velocity: u.from_rad(j.velocity),
            cycles: j.stall,
        };
        Some((kind, p.on_stall))
    } else if j.follow >= p.following_cycles {
        let kind = FaultKind::FollowingError {
            error: u.from_rad(e),
            tolerance: u.from_rad(jp.following_error),
            cycles: j.follow,
        };
        Some((kind, p.on_following_error))
    } else {
        None
    }
}
