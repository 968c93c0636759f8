//! One bus's share of a control cycle: goals out, feedback in, tracking,
//! fault detection, lead identification and telemetry. Everything it needs
//! is allocated when it is built; a cycle allocates nothing.

use std::time::Duration;

use crossbeam_channel::Sender;
use servobus_driver::{Bus, BusError, Clock, MissingReason, Transport, TransportError};
use servobus_protocol::registers::{addr, ByteOrder, Register};
use servobus_protocol::StatusFlags;
use servobus_timing::Plan;
use servobus_trajectory::JointState;

use crate::config::{BusConfig, JointMap, Units};
use crate::error::RunError;
use crate::fault::{Fault, FaultKind};
use crate::options::{FaultPolicy, Lead, Reaction};
use crate::report::{BusReport, JointReport};
use crate::stats::{Histogram, RunningError};
use crate::telemetry::{CycleSample, JointSample, Telemetry, SAMPLE_JOINTS};

/// How long the lead takes to ramp in once identified, s.
const LEAD_RAMP_S: f64 = 0.5;
/// Readings of moving joints needed before the lag is identified.
const IDENTIFY_READINGS: u32 = 60;
/// Smallest change of the identified lag that moves the lead, s.
const LEAD_STEP: f64 = 0.000_5;
/// Slowest path speed that counts for identification, rad/s.
const IDENTIFY_MIN_SPEED: f64 = 0.05;

/// The tracking state of one joint.
#[derive(Debug)]
pub(crate) struct JointTrack {
    /// Index in the robot's joint order.
    pub robot_index: usize,
    pub name: String,
    pub id: u8,
    map: JointMap,
    /// The joint limits as ticks, rounded inwards: every goal sent lies in
    /// `lo_tick..=hi_tick`.
    lo_tick: i32,
    hi_tick: i32,
    goal_tick: i32,
    goal_rad: f64,
    clamped: bool,
    measured: Option<f64>,
    measured_at: Duration,
    prev: Option<(f64, Duration)>,
    velocity: f64,
    planned: f64,
    error: f64,
    fresh: bool,
    flags: StatusFlags,
    /// Why the last read of it failed.
    why_missing: Option<MissingReason>,
    err: RunningError,
    clamps: u64,
    follow: u32,
    stall: u32,
    missing: u32,
}

impl JointTrack {
    fn new(robot_index: usize, joint: &crate::config::JointConfig, units: Units) -> Self {
        let map = JointMap::new(joint, units);
        let a = map.raw_ticks(map.min_rad);
        let b = map.raw_ticks(map.max_rad);
        let max = i32::try_from(joint.model.max_position()).unwrap_or(i32::MAX);
        // A small epsilon keeps a limit that falls exactly on a tick (up to
        // rounding) on that tick.
        let lo = (a.min(b) - 1e-6).ceil().clamp(0.0, f64::from(max)) as i32;
        let hi = (a.max(b) + 1e-6).floor().clamp(0.0, f64::from(max)) as i32;
        JointTrack {
            robot_index,
            name: joint.name.clone(),
            id: joint.id,
            map,
            lo_tick: lo.min(hi),
            hi_tick: hi,
            goal_tick: lo,
            goal_rad: map.from_ticks(lo),
            clamped: false,
            measured: None,
            measured_at: Duration::ZERO,
            prev: None,
            velocity: 0.0,
            planned: 0.0,
            error: 0.0,
            fresh: false,
            flags: StatusFlags(0),
            why_missing: None,
            err: RunningError::default(),
            clamps: 0,
            follow: 0,
            stall: 0,
            missing: 0,
        }
    }

    /// The goal for `rad`: clamped to the joint limits at the very last
    /// step, in ticks. Counts a clamp.
    fn set_goal(&mut self, rad: f64) {
        let c = self.map.goal(rad);
        // Rounding to a tick can land half a tick beyond a limit: keep the
        // tick inside too.
        let tick = c.value.clamp(self.lo_tick, self.hi_tick);
        self.clamped = c.clamped;
        if c.clamped {
            self.clamps += 1;
        }
        self.goal_tick = tick;
        // The commanded angle as planned (inside the limits), before the
        // tick rounding: what telemetry reports and holds fall back to.
        self.goal_rad = if c.value == tick {
            self.map.clamp(rad).value
        } else {
            self.map.from_ticks(tick)
        };
    }

    fn observe(&mut self, ticks: i32, at: Duration) {
        let p = self.map.from_ticks(ticks);
        if let Some((q, t)) = self.prev {
            if at > t {
                self.velocity = (p - q) / (at - t).as_secs_f64();
            }
        }
        self.prev = Some((p, at));
        self.measured = Some(p);
        self.measured_at = at;
        self.fresh = true;
        self.missing = 0;
    }

    /// Where the joint should hold: its fresh reading, else its last goal.
    fn hold_position(&self, stale: bool) -> f64 {
        match self.measured {
            Some(p) if !stale => self.map.clamp(p).value,
            _ => self.goal_rad,
        }
    }
}

/// How the lead evolves.
#[derive(Debug, Clone, Copy)]
enum LeadState {
    Fixed(f64),
    /// The lead is identified while the path plays, and refined: every
    /// [`IDENTIFY_READINGS`] readings the estimate is updated and, when it
    /// moved, the lead ramps to it.
    Auto {
        max: f64,
        /// Sum of (error + lead x velocity) x velocity over the readings:
        /// the error against the path is velocity x (lag - lead), so this
        /// estimates the lag whatever lead was in force.
        sev: f64,
        svv: f64,
        /// Readings since the estimate was last updated.
        n: u32,
        ramp: Ramp,
    },
}

/// A smooth change of the lead from `from` to `to`, starting at `x0`.
#[derive(Debug, Clone, Copy)]
struct Ramp {
    from: f64,
    to: f64,
    x0: f64,
}

impl Ramp {
    fn at(&self, x: f64) -> f64 {
        let u = ((x - self.x0) / LEAD_RAMP_S).clamp(0.0, 1.0);
        self.from + (self.to - self.from) * u * u * u * (10.0 + u * (-15.0 + 6.0 * u))
    }

    fn done(&self, x: f64) -> bool {
        x >= self.x0 + LEAD_RAMP_S
    }
}

impl LeadState {
    fn at(&self, x: f64) -> f64 {
        match self {
            LeadState::Fixed(l) => *l,
            LeadState::Auto { ramp, .. } => ramp.at(x),
        }
    }
}

/// What a cycle's timing was.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CycleTiming {
    pub index: u64,
    pub deadline: Duration,
    pub woke: Duration,
    pub skipped: u64,
}

/// One bus of a run.
pub(crate) struct BusLoop<T: Transport, C: Clock> {
    pub index: usize,
    pub name: String,
    pub bus: Bus<T, C>,
    clock: C,
    goal_reg: &'static Register,
    pos_reg: &'static Register,
    order: ByteOrder,
    plan: Plan,
    pub joints: Vec<JointTrack>,
    ids: Vec<u8>,
    data: Vec<u8>,
    zeros: Vec<u8>,
    period: Duration,
    /// Clock time of cycle 0.
    pub start: Duration,
    units: Units,
    policy: FaultPolicy,
    lead: LeadState,
    telemetry: Option<Sender<Telemetry>>,
    sample: CycleSample,
    // Figures.
    pub cycles: u64,
    overruns: u64,
    busy_total: Duration,
    busy_max: Duration,
    pub period_error: Histogram,
    first_woke: Option<Duration>,
    last: Option<CycleTiming>,
    missed: u64,
    pub dropped: u64,
    /// The port failed: nothing more is sent on this bus.
    pub gone: bool,
    timing: CycleTiming,
}

/// Whether a bus error means the port is gone (not a servo's silence).
fn port_gone(e: &BusError) -> Option<String> {
    match e {
        BusError::Transport(TransportError::TimedOut) => None,
        BusError::Transport(t) => Some(t.to_string()),
        _ => None,
    }
}

impl<T: Transport, C: Clock> BusLoop<T, C> {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        index: usize,
        config: &BusConfig,
        first_joint: usize,
        units: Units,
        report_units: Units,
        bus: Bus<T, C>,
        rate_hz: f64,
        period: Duration,
        policy: FaultPolicy,
        lead: Lead,
        telemetry: Option<Sender<Telemetry>>,
    ) -> Result<Self, RunError> {
        let plan = config.plan(rate_hz).map_err(|source| RunError::Plan {
            bus: config.name.clone(),
            source,
        })?;
        let series = bus.settings().series;
        if let Some(j) = config.joints.iter().find(|j| j.model.series != series) {
            return Err(RunError::Invalid(format!(
                "bus `{}`: joint `{}` is a {} ({:?} series) but the bus talks {:?}",
                config.name, j.name, j.model.name, j.model.series, series
            )));
        }
        let map = series.map();
        let (Some(goal_reg), Some(pos_reg)) =
            (map.at(addr::GOAL_POSITION), map.at(addr::PRESENT_POSITION))
        else {
            return Err(RunError::Invalid(format!(
                "the {series:?} register map has no goal or present position"
            )));
        };
        let joints: Vec<JointTrack> = config
            .joints
            .iter()
            .enumerate()
            .map(|(i, j)| JointTrack::new(first_joint + i, j, units))
            .collect();
        let n = joints.len();
        let lead = match lead {
            Lead::None => LeadState::Fixed(0.0),
            Lead::Fixed(d) => LeadState::Fixed(d.as_secs_f64()),
            Lead::Auto { max } => LeadState::Auto {
                max: max.as_secs_f64(),
                sev: 0.0,
                svv: 0.0,
                n: 0,
                // No lead until the first estimate (a finished ramp to 0).
                ramp: Ramp {
                    from: 0.0,
                    to: 0.0,
                    x0: f64::NEG_INFINITY,
                },
            },
        };
        let timing = CycleTiming {
            index: 0,
            deadline: Duration::ZERO,
            woke: Duration::ZERO,
            skipped: 0,
        };
        Ok(BusLoop {
            index,
            name: config.name.clone(),
            ids: config.joints.iter().map(|j| j.id).collect(),
            data: vec![0; n * usize::from(goal_reg.size)],
            zeros: vec![0; n],
            clock: bus.clock().clone(),
            bus,
            goal_reg,
            pos_reg,
            order: series.byte_order(),
            plan,
            joints,
            period,
            start: Duration::ZERO,
            units: report_units,
            policy,
            lead,
            telemetry,
            sample: CycleSample::new(index, 0, 0.0),
            cycles: 0,
            overruns: 0,
            busy_total: Duration::ZERO,
            busy_max: Duration::ZERO,
            period_error: Histogram::new(Duration::from_millis(100)),
            first_woke: None,
            last: None,
            missed: 0,
            dropped: 0,
            gone: false,
            timing,
        })
    }

    /// The reaction of this bus's policy to a lost port.
    pub fn policy_port_gone(&self) -> Reaction {
        self.policy.on_port_gone
    }

    /// Reads every servo's position patiently (start-up is not timed; see
    /// [`Bus::sync_read_patiently`]), sets the goals there (clamped into the
    /// limits) and enables torque.
    pub fn startup(&mut self, enable_torque: bool) -> Result<(), RunError> {
        self.read_start_positions()?;
        self.hold_and_enable(enable_torque)
    }

    fn read_start_positions(&mut self) -> Result<(), RunError> {
        let read = self
            .bus
            .sync_read_patiently(self.pos_reg.address, self.pos_reg.size, &self.ids)
            .map_err(|source| RunError::Startup {
                bus: self.name.clone(),
                what: "reading the start positions",
                source,
            })?;
        let now = self.clock.now();
        for (j, r) in self.joints.iter_mut().zip(read.iter()) {
            let reason = match r {
                Ok(reply) => match self.pos_reg.decode(reply.data, self.order) {
                    Ok(t) => {
                        j.observe(t, now);
                        continue;
                    }
                    Err(_) => "it reported an impossible position".to_owned(),
                },
                Err(m) => m.reason.to_string(),
            };
            return Err(RunError::NoServo {
                bus: self.name.clone(),
                id: j.id,
                joint: j.name.clone(),
                reason,
            });
        }
        Ok(())
    }

    /// Sets every goal to the measured start position and enables torque.
    fn hold_and_enable(&mut self, enable_torque: bool) -> Result<(), RunError> {
        for j in &mut self.joints {
            let p = j.measured.unwrap_or(0.0);
            j.set_goal(p);
            // Not a clamp of the plan: the joint started outside its limits.
            j.clamps = 0;
            j.prev = None;
            j.fresh = false;
        }
        self.encode_goals();
        if enable_torque {
            let e = |what| {
                move |e| RunError::Startup {
                    bus: String::new(),
                    what,
                    source: e,
                }
            };
            let named = |r: RunError| match r {
                RunError::Startup { what, source, .. } => RunError::Startup {
                    bus: self.name.clone(),
                    what,
                    source,
                },
                other => other,
            };
            self.bus
                .sync_write(self.goal_reg.address, &self.ids, &self.data)
                .map_err(e("setting the goals to the present positions"))
                .map_err(named)?;
            let ones = vec![1u8; self.ids.len()];
            self.bus
                .sync_write(addr::TORQUE_ENABLE, &self.ids, &ones)
                .map_err(e("enabling torque"))
                .map_err(named)?;
        }
        Ok(())
    }

    /// Positions read at start-up (rad), into `out` (robot order).
    pub fn present(&self, out: &mut [f64]) {
        for j in &self.joints {
            if let Some(slot) = out.get_mut(j.robot_index) {
                *slot = j.measured.unwrap_or(j.goal_rad);
            }
        }
    }

    pub fn lead_at(&self, x: f64) -> f64 {
        self.lead.at(x)
    }

    /// Records the start of a cycle.
    pub fn begin(&mut self, mut timing: CycleTiming) {
        timing.skipped = self
            .last
            .map_or(0, |l| timing.index.saturating_sub(l.index + 1));
        if let Some(last) = self.last {
            let n = u32::try_from(timing.index.saturating_sub(last.index)).unwrap_or(u32::MAX);
            let expected = self.period * n;
            let interval = timing.woke.saturating_sub(last.woke);
            let err = if interval > expected {
                interval - expected
            } else {
                expected - interval
            };
            self.period_error.record(err);
        }
        self.first_woke.get_or_insert(timing.woke);
        self.overruns += timing.skipped;
        self.cycles += 1;
        self.timing = timing;
        self.last = Some(timing);
        for j in &mut self.joints {
            j.fresh = false;
        }
    }

    fn encode_goals(&mut self) {
        let size = usize::from(self.goal_reg.size);
        for (j, out) in self.joints.iter().zip(self.data.chunks_exact_mut(size)) {
            // The tick is inside the servo's range, so it always encodes.
            let _ = self.goal_reg.encode(j.goal_tick, self.order, out);
        }
    }

    /// Maps, clamps and sends the goals for `cmd` (robot order, rad).
    pub fn write(&mut self, cmd: &[JointState]) -> Result<(), String> {
        for j in &mut self.joints {
            let rad = cmd.get(j.robot_index).map_or(f64::NAN, |s| s.position);
            j.set_goal(rad);
        }
        self.send_goals()
    }

    /// Sends the current goals again.
    fn send_goals(&mut self) -> Result<(), String> {
        if self.gone {
            return Ok(());
        }
        self.encode_goals();
        match self
            .bus
            .sync_write(self.goal_reg.address, &self.ids, &self.data)
        {
            Ok(()) => Ok(()),
            Err(e) => match port_gone(&e) {
                Some(msg) => {
                    self.gone = true;
                    Err(msg)
                }
                None => Ok(()),
            },
        }
    }

    /// Holds every joint where it is (its fresh reading, else its last goal)
    /// and sends it now. Fills `out` (robot order) with the positions.
    pub fn hold_positions(&self, out: &mut [f64]) {
        let stale = self.stale_after();
        let now = self.clock.now();
        for j in &self.joints {
            if let Some(slot) = out.get_mut(j.robot_index) {
                *slot = j.hold_position(now.saturating_sub(j.measured_at) > stale);
            }
        }
    }

    /// Disables torque on every servo of the bus.
    pub fn torque_off(&mut self) {
        if !self.gone {
            let _ = self
                .bus
                .sync_write(addr::TORQUE_ENABLE, &self.ids, &self.zeros);
        }
    }

    fn stale_after(&self) -> Duration {
        let every = u32::try_from(self.plan.read_every()).unwrap_or(u32::MAX);
        self.period * every.saturating_mul(2)
    }

    /// Reads the feedback this cycle's plan asks for. Returns the time of
    /// the reading, s since the start, or the port's failure.
    pub fn read(&mut self) -> Result<f64, String> {
        let k = self.timing.index;
        let range = self.plan.reads_in_cycle(k);
        if !self.gone && !range.is_empty() {
            let now = self.clock.now();
            // Re-ask missing servos only while the cycle leaves room.
            let budget = (self.timing.deadline + self.period)
                .saturating_sub(now)
                .saturating_sub(self.period / 8);
            let ids = &self.ids[range.clone()];
            match self
                .bus
                .sync_read_within(self.pos_reg.address, self.pos_reg.size, ids, budget)
            {
                Ok(read) => {
                    let at = self.clock.now();
                    for (i, r) in read.iter().enumerate() {
                        let Some(j) = self.joints.get_mut(range.start + i) else {
                            continue;
                        };
                        match r {
                            Ok(reply) => match self.pos_reg.decode(reply.data, self.order) {
                                Ok(t) => {
                                    j.observe(t, at);
                                    j.flags = reply.flags;
                                }
                                Err(_) => {
                                    j.missing += 1;
                                    self.missed += 1;
                                }
                            },
                            Err(m) => {
                                j.missing += 1;
                                j.why_missing = Some(m.reason);
                                self.missed += 1;
                            }
                        }
                    }
                }
                Err(e) => {
                    if let Some(msg) = port_gone(&e) {
                        self.gone = true;
                        return Err(msg);
                    }
                }
            }
        }
        Ok(self.seconds(self.clock.now()))
    }

    fn seconds(&self, t: Duration) -> f64 {
        t.saturating_sub(self.start).as_secs_f64()
    }
}

/// What tracking found in a cycle.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct TrackInput {
    /// Whether a planned path is playing (the lag is identified only then).
    pub main: bool,
    /// The cycle's nominal time, s.
    pub t: f64,
}

impl<T: Transport, C: Clock> BusLoop<T, C> {
    /// Updates every joint's error against `reference` (robot order, the
    /// path at the time of the reading), identifies the lag, and detects
    /// faults. Returns the first fault found.
    pub fn track(&mut self, reference: &[JointState], input: TrackInput) -> Option<Fault> {
        let p = self.policy;
        let mut found: Option<(usize, FaultKind, Reaction)> = None;
        let mut sev = 0.0;
        let mut svv = 0.0;
        let mut n = 0u32;
        let lead = self.lead.at(input.t);
        for (i, j) in self.joints.iter_mut().enumerate() {
            let r = reference.get(j.robot_index).copied().unwrap_or_default();
            j.planned = r.position;
            if j.missing > 0 && j.missing >= p.missing_cycles && found.is_none() {
                found = Some((
                    i,
                    FaultKind::Missing {
                        cycles: j.missing,
                        reason: j
                            .why_missing
                            .map_or_else(|| "unreadable reply".to_owned(), |r| r.to_string()),
                    },
                    p.on_missing,
                ));
            }
            if !j.fresh {
                continue;
            }
            let Some(m) = j.measured else { continue };
            let e = r.position - m;
            j.error = e;
            j.err.record(e);
            if input.main && r.velocity.abs() > IDENTIFY_MIN_SPEED {
                sev += (e + lead * r.velocity) * r.velocity;
                svv += r.velocity * r.velocity;
                n += 1;
            }
            let stalled = e.abs() > p.stall_error
                && r.velocity.abs() >= p.stall_min_velocity
                && (j.velocity.abs() < p.stall_ratio * r.velocity.abs()
                    || j.velocity.signum() != r.velocity.signum());
            j.stall = if stalled { j.stall + 1 } else { 0 };
            j.follow = if e.abs() > p.following_error {
                j.follow + 1
            } else {
                0
            };
            if found.is_some() {
                continue;
            }
            let flags = j.flags.bits() & p.status_mask;
            if flags != 0 {
                found = Some((
                    i,
                    FaultKind::Status {
                        flags,
                        names: StatusFlags(flags).to_string(),
                    },
                    p.on_status,
                ));
            } else if j.stall >= p.stall_cycles {
                let u = self.units;
                found = Some((
                    i,
                    FaultKind::Stall {
                        error: u.from_rad(e),
                        planned_velocity: u.from_rad(r.velocity),
                        measured_velocity: u.from_rad(j.velocity),
                        cycles: j.stall,
                    },
                    p.on_stall,
                ));
            } else if j.follow >= p.following_cycles {
                let u = self.units;
                found = Some((
                    i,
                    FaultKind::FollowingError {
                        error: u.from_rad(e),
                        tolerance: u.from_rad(p.following_error),
                        cycles: j.follow,
                    },
                    p.on_following_error,
                ));
            }
        }
        if let LeadState::Auto {
            max,
            sev: s_ev,
            svv: s_vv,
            n: count,
            ramp,
        } = &mut self.lead
        {
            *s_ev += sev;
            *s_vv += svv;
            *count += n;
            // A new estimate once enough readings came in and the last
            // change has finished; small changes are not worth a ramp.
            if *count >= IDENTIFY_READINGS && *s_vv > 0.0 && ramp.done(input.t) {
                *count = 0;
                let lag = (*s_ev / *s_vv).clamp(0.0, *max);
                if (lag - ramp.to).abs() > LEAD_STEP {
                    *ramp = Ramp {
                        from: ramp.to,
                        to: lag,
                        x0: input.t,
                    };
                }
            }
        }
        found.map(|(i, kind, reaction)| {
            let j = &self.joints[i];
            self.fault(kind, Some(i), reaction, j.id)
        })
    }

    /// A fault on this bus, for joint `joint` (index in the bus).
    pub fn fault(
        &self,
        kind: FaultKind,
        joint: Option<usize>,
        reaction: Reaction,
        id: u8,
    ) -> Fault {
        let joint = joint.and_then(|i| self.joints.get(i));
        Fault {
            kind,
            bus: self.name.clone(),
            joint: joint.map(|j| j.name.clone()),
            servo_id: joint.map(|_| id),
            time_s: self.timing.index as f64 * self.period.as_secs_f64(),
            cycle: self.timing.index,
            reaction,
            units: self.units.name(),
        }
    }

    /// Records the end of the cycle's work and publishes its telemetry.
    pub fn finish_cycle(&mut self, lead: f64) {
        let now = self.clock.now();
        let busy = now.saturating_sub(self.timing.woke);
        self.busy_total += busy;
        self.busy_max = self.busy_max.max(busy);
        let Some(tx) = &self.telemetry else { return };
        let u = self.units;
        let stale_after = self.stale_after();
        let k = self.timing.index;
        let mut sample = self.sample;
        sample.cycle = k;
        sample.time_s = k as f64 * self.period.as_secs_f64();
        sample.lateness = self.timing.woke.saturating_sub(self.timing.deadline);
        sample.busy = busy;
        sample.skipped = self.timing.skipped;
        sample.lead = Duration::from_secs_f64(lead.max(0.0));
        for chunk in self.joints.chunks(SAMPLE_JOINTS) {
            sample.clear_joints();
            for j in chunk {
                let age = now.saturating_sub(j.measured_at);
                sample.push(JointSample {
                    joint: j.robot_index,
                    commanded: u.from_rad(j.goal_rad),
                    planned: u.from_rad(j.planned),
                    measured: j.measured.map(|m| u.from_rad(m)),
                    error: u.from_rad(j.error),
                    velocity: u.from_rad(j.velocity),
                    feedback_age: age,
                    stale: age > stale_after,
                    clamped: j.clamped,
                    flags: j.flags,
                    missing_reads: j.missing,
                });
            }
            if tx.try_send(Telemetry::Cycle(sample)).is_err() {
                self.dropped += 1;
            }
        }
    }

    /// Sends a message that is not a cycle sample (fault, finish); counted
    /// as dropped when the channel is full.
    pub fn publish(&mut self, message: Telemetry) {
        if let Some(tx) = &self.telemetry {
            if tx.try_send(message).is_err() {
                self.dropped += 1;
            }
        }
    }

    /// Sends the goals of a hold at `positions` (robot order, rad) now.
    pub fn send_hold(&mut self, positions: &[f64]) -> Result<(), String> {
        for j in &mut self.joints {
            let rad = positions.get(j.robot_index).copied().unwrap_or(j.goal_rad);
            j.set_goal(rad);
        }
        self.send_goals()
    }

    /// The bus's figures.
    pub fn report(&self) -> BusReport {
        let c = self.bus.counters();
        let period = self.period.as_secs_f64();
        BusReport {
            name: self.name.clone(),
            cycles: self.cycles,
            overruns: self.overruns,
            utilisation: if self.cycles == 0 {
                0.0
            } else {
                self.busy_total.as_secs_f64() / self.cycles as f64 / period
            },
            peak_utilisation: self.busy_max.as_secs_f64() / period,
            planned_utilisation: self.plan.utilisation(),
            read_every: self.plan.read_every(),
            timeouts: c.timeouts,
            retries: c.retries,
            missed_replies: self.missed,
        }
    }

    /// The joints' tracking figures, in `units`.
    pub fn joint_reports(&self) -> impl Iterator<Item = (usize, JointReport)> + '_ {
        let u = self.units;
        self.joints.iter().map(move |j| {
            (
                j.robot_index,
                JointReport {
                    name: j.name.clone(),
                    rms_error: u.from_rad(j.err.rms()),
                    max_error: u.from_rad(j.err.max_abs()),
                    readings: j.err.count(),
                    clamps: j.clamps,
                },
            )
        })
    }

    /// `(first woke, last woke, last deadline)` of the cycles run.
    pub fn span(&self) -> Option<(Duration, Duration, Duration)> {
        Some((self.first_woke?, self.last?.woke, self.last?.deadline))
    }
}
