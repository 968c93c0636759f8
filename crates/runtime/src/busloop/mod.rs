//! One bus's share of a control cycle, built from named parts: writing goals
//! ([`goals`]), reading feedback ([`feedback`]), tracking with fault
//! detection ([`tracking`]), lead estimation ([`lead`]), timing figures
//! ([`counters`]) and telemetry ([`publish`]). Everything is allocated when
//! the loop is built; a cycle allocates nothing.
//!
//! Wheel joints (`mode: wheel`, [`wheels`]) take part in the same cycle
//! with speeds instead of positions: their commanded speed ramps toward
//! the timeline's target speed within their acceleration (and jerk)
//! limits and goes out as goal speed in a SYNC WRITE frame of its own,
//! after the goal positions; their present speed is read with the
//! position (4 bytes from 56) and published, and they are not tracked
//! against the path. Start-up ([`servo_setup`]) refuses a servo whose
//! operating mode is not its joint's and writes the joints' RAM `servo:`
//! settings. A bus without wheels writes and reads exactly what it did
//! before wheels existed.

mod cycle_times;
mod deadlines;
mod feedback;
mod goals;
mod grasp;
mod lead;
mod publish;
mod servo_setup;
mod tracking;
mod wheels;

use std::time::Duration;

use crossbeam_channel::Sender;
use servobus_driver::{Bus, Clock, Transport};
use servobus_protocol::registers::{addr, Register, Series};
use servobus_timing::Plan;
use servobus_trajectory::JointState;

pub(crate) use cycle_times::CycleTiming;
pub(crate) use goals::reachable;

use cycle_times::CycleTimes;
use deadlines::{LinkLearner, Probe};
use feedback::Feedback;
use goals::GoalWriter;
use grasp::GraspWatch;
use lead::LeadEstimator;
use publish::{Publisher, SampleTiming};
use servo_setup::ServoSetup;
use tracking::Tracker;
use wheels::WheelWriter;

use crate::config::{BusConfig, Units};
use crate::error::{PortGone, RunError};
use crate::fault::{Fault, FaultKind, STALL_PUSH};
use crate::grasp::GraspReport;
use crate::options::{FaultPolicy, Lead};
use crate::report::{BusReport, JointReport};
use crate::stats::Histogram;
use crate::telemetry::{StallEvent, Telemetry};

/// What a [`BusLoop`] is built from.
pub(crate) struct LoopConfig<'a> {
    /// Index of the bus in the robot's bus order.
    pub index: usize,
    pub bus: &'a BusConfig,
    /// Index of the bus's first joint in the robot's joint order.
    pub first_joint: usize,
    /// The robot file's angle units, and the report's.
    pub units: Units,
    pub report_units: Units,
    pub rate_hz: f64,
    pub period: Duration,
    pub policy: FaultPolicy,
    pub lead: Lead,
    pub telemetry: Option<Sender<Telemetry>>,
}

/// One bus of a run.
pub(crate) struct BusLoop<T: Transport> {
    pub index: usize,
    pub name: String,
    pub bus: Bus<T>,
    clock: T::Clock,
    plan: Plan,
    period: Duration,
    /// Clock time of cycle 0.
    pub start: Duration,
    /// The report's units.
    units: Units,
    policy: FaultPolicy,
    goals: GoalWriter,
    /// The wheels' goal speeds (none on a bus of position joints).
    wheels: WheelWriter,
    /// The grasps its joints make.
    grasps: GraspWatch,
    /// The operating modes checked and the `servo:` settings written at
    /// start-up.
    setup: ServoSetup,
    /// The EEPROM `servo:` settings the servos held otherwise at start-up.
    eeprom_differences: Vec<crate::report::SettingDifference>,
    feedback: Feedback,
    track: Tracker,
    lead: LeadEstimator,
    counters: CycleTimes,
    out: Publisher,
    timing: CycleTiming,
    /// The adapter latency in force, learned from the replies.
    link: LinkLearner,
    /// The start-up measurement of the adapter (`latency_us: auto`).
    probe: Probe,
    /// The port failed: nothing more is sent on this bus.
    gone: bool,
    /// The time of this cycle's reading, on the bus's clock (see
    /// [`read`](Self::read)): the path sampled for tracking is the path then.
    read_at: Duration,
}

impl<T: Transport> BusLoop<T> {
    /// The loop of `c.bus` on `bus`.
    ///
    /// # Errors
    ///
    /// [`RunError::Plan`] when the rate does not fit the bus,
    /// [`RunError::Series`] when a joint's servo is not of the bus's series.
    pub fn new(c: LoopConfig<'_>, bus: Bus<T>) -> Result<Self, RunError> {
        let config = c.bus;
        let plan = config.plan(c.rate_hz).map_err(|source| RunError::Plan {
            bus: config.name.clone(),
            source,
        })?;
        let series = bus.settings().series;
        if let Some(j) = config.joints.iter().find(|j| j.model.series != series) {
            return Err(RunError::Series {
                bus: config.name.clone(),
                joint: j.name.clone(),
                model: j.model.name,
                joint_series: j.model.series,
                bus_series: series,
            });
        }
        let map = series.map();
        let (Some(goal_reg), Some(pos_reg)) =
            (map.at(addr::GOAL_POSITION), map.at(addr::PRESENT_POSITION))
        else {
            return Err(RunError::NoPositionRegisters(series));
        };
        let order = series.byte_order();
        let (speed_reg, feedback_speed) = wheel_registers(config, series)?;
        let every = u32::try_from(plan.read_every()).unwrap_or(u32::MAX);
        let stale_after = c.period * every.saturating_mul(2);
        let ids = config.joints.iter().map(|j| j.id).collect();
        let bus_latency = bus.settings().link.latency;
        Ok(BusLoop {
            index: c.index,
            name: config.name.clone(),
            clock: bus.clock().clone(),
            bus,
            plan,
            period: c.period,
            start: Duration::ZERO,
            units: c.report_units,
            policy: c.policy,
            goals: GoalWriter::new(config, c.first_joint, c.units, goal_reg, order),
            wheels: WheelWriter::new(
                config,
                c.first_joint,
                c.units,
                speed_reg,
                order,
                c.period.as_secs_f64(),
            ),
            setup: ServoSetup::new(config, map.at(addr::MODE)),
            eeprom_differences: Vec::new(),
            grasps: GraspWatch::new(config, c.first_joint, map, order),
            feedback: Feedback::new(pos_reg, feedback_speed, order, ids),
            track: Tracker::new(
                config,
                c.first_joint,
                c.units,
                c.report_units,
                c.policy,
                stale_after,
            ),
            lead: lead_estimator(c.lead, config, c.period),
            counters: CycleTimes::new(),
            out: Publisher::new(c.index, c.telemetry),
            timing: CycleTiming {
                index: 0,
                deadline: Duration::ZERO,
                woke: Duration::ZERO,
                skipped: 0,
            },
            link: LinkLearner::new(bus_latency, !config.latency_auto),
            probe: Probe::default(),
            gone: false,
            read_at: Duration::ZERO,
        })
    }

    /// Reads every servo's position patiently, sets the goals there
    /// (clamped into the limits) and, when asked, checks every servo's
    /// operating mode against its joint ([`ServoSetup::check_modes`]),
    /// turns the servos' own motion profiles off
    /// ([`GoalWriter::release_profiles`], which leaves the wheels' goal
    /// speed at 0), writes the joints' RAM `servo:` settings
    /// ([`ServoSetup::write_settings`]: a joint's own `acceleration` wins
    /// over the release) and enables torque.
    ///
    /// # Errors
    ///
    /// As [`Feedback::startup`] and [`ServoSetup::check_modes`];
    /// [`RunError::Startup`] when the goals, the settings or the torque
    /// cannot be written.
    pub fn startup(&mut self, enable_torque: bool) -> Result<(), RunError> {
        if self.link.learns() {
            self.probe =
                deadlines::probe(&mut self.bus, &self.clock, &mut self.link, &self.feedback);
        }
        self.bus.set_latency(self.link.in_force());
        self.feedback
            .startup(&mut self.bus, &self.name, &mut self.track)?;
        for (i, j) in self.track.joints.iter().enumerate() {
            self.goals.start_at(i, j.measured.unwrap_or(0.0));
        }
        self.track.settle();
        if !enable_torque {
            return Ok(());
        }
        self.setup.check_modes(&mut self.bus, &self.name)?;
        self.eeprom_differences = self.setup.compare_eeprom(&mut self.bus);
        let failed = |what| {
            let bus = self.name.clone();
            move |source| RunError::Startup { bus, what, source }
        };
        self.goals
            .send_checked(&mut self.bus)
            .map_err(failed("setting the goals to the present positions"))?;
        self.goals
            .release_profiles(&mut self.bus)
            .map_err(failed("turning off the servos' own acceleration ramps"))?;
        self.wheels
            .send_checked(&mut self.bus)
            .map_err(failed("setting the wheels' speeds to 0"))?;
        self.setup.write_settings(&mut self.bus, &self.name)?;
        self.goals
            .torque(&mut self.bus, true)
            .map_err(failed("enabling torque"))
    }

    /// Positions read at start-up (rad), into `out` (robot order); a
    /// wheel's is its rest, 0, so that no path moves to where it stands.
    pub fn present(&self, out: &mut [f64]) {
        for (g, j) in self.goals.joints.iter().zip(&self.track.joints) {
            if let Some(slot) = out.get_mut(g.robot_index) {
                *slot = if g.wheel {
                    0.0
                } else {
                    j.measured.unwrap_or(g.rad)
                };
            }
        }
    }

    /// Whether every wheel of the bus is commanded to rest (true on a bus
    /// without wheels): a run ends only then, so that the last goal speed
    /// sent is 0.
    pub fn wheels_at_rest(&self) -> bool {
        self.wheels.at_rest()
    }

    /// The lead at path time `x`, s.
    pub fn lead_at(&self, x: f64) -> f64 {
        self.lead.at(x)
    }

    /// Records the start of a cycle.
    pub fn begin(&mut self, mut timing: CycleTiming) {
        self.counters.begin(&mut timing, self.period);
        self.timing = timing;
        self.track.begin();
    }

    /// From now on the run is a live session (it follows live targets): a
    /// joint that stalls is held pressed with bounded effort
    /// ([`STALL_PUSH`](crate::fault::STALL_PUSH)), reported, and does not
    /// end the run. The lane calls it in a cycle whose path is live.
    pub fn live_session(&mut self) {
        self.track.live_session();
    }

    /// Maps, clamps and sends the goals for `cmd` (robot order, rad), and
    /// the wheels' speeds one ramp step toward `speeds` (robot order,
    /// rad/s; read for wheel joints only), after taking in the efforts of
    /// the grasps asked (`grasps`, robot order; see [`GraspWatch`]). A pressed joint's goal is kept
    /// within its press's bound; one whose goal came back within it is let
    /// go.
    pub fn write(
        &mut self,
        cmd: &[JointState],
        speeds: &[f64],
        grasps: &[Option<f64>],
    ) -> Result<(), PortGone> {
        let t = self.timing.index as f64 * self.period.as_secs_f64();
        let out = &mut self.out;
        self.grasps
            .update(&mut self.bus, grasps, t, &mut self.track, |joint, event| {
                out.publish(Telemetry::Grasp(GraspReport {
                    joint,
                    time_s: t,
                    event,
                }));
            })?;
        self.release_presses(cmd);
        let joints = &self.track.joints;
        self.goals
            .aim_within(cmd, |i| joints.get(i).and_then(|j| j.press));
        self.wheels.aim(speeds);
        self.send_goals()
    }

    /// Lets go every pressed joint whose goal in `cmd` no longer pushes
    /// beyond its bound, counts the others' held cycle, and publishes the
    /// change.
    fn release_presses(&mut self, cmd: &[JointState]) {
        for i in 0..self.track.joints.len() {
            let Some(j) = self.track.joints.get_mut(i) else {
                continue;
            };
            j.held = false;
            let Some(press) = j.press else { continue };
            let goal = cmd.get(j.robot_index).map_or(f64::NAN, |s| s.position);
            if press.released_by(goal) || goal.is_nan() {
                j.press = None;
                self.publish_stall(i, false, press.dir);
            } else {
                j.held = true;
                j.pressed_cycles += 1;
            }
        }
    }

    /// Publishes that joint `i` (of the bus) stalled and is held (`held`),
    /// or was let go, pushed in direction `dir`.
    fn publish_stall(&mut self, i: usize, held: bool, dir: f64) {
        let Some(j) = self.track.joints.get(i) else {
            return;
        };
        let u = self.units;
        let event = StallEvent {
            joint: j.robot_index,
            bus: self.index,
            servo_id: j.id,
            held,
            time_s: self.timing.index as f64 * self.period.as_secs_f64(),
            cycle: self.timing.index,
            position: u.from_rad(j.measured.unwrap_or(j.planned)),
            push: u.from_rad(
                dir * j
                    .press
                    .map(|p| p.push)
                    .or(j.grasp_push)
                    .unwrap_or(STALL_PUSH),
            ),
        };
        self.out.publish(Telemetry::Stall(event));
    }

    /// Sends the goals of a hold at `positions` (robot order, rad) now.
    pub fn send_hold(&mut self, positions: &[f64]) -> Result<(), PortGone> {
        self.goals.aim_at(positions);
        self.send_goals()
    }

    fn send_goals(&mut self) -> Result<(), PortGone> {
        if self.gone {
            return Ok(());
        }
        let mut sent = self.goals.send(&mut self.bus);
        if sent.is_ok() && self.wheels.any() {
            sent = self.wheels.send(&mut self.bus);
        }
        self.gone = sent.is_err();
        sent
    }

    /// Reads the feedback this cycle's plan asks for. Returns the time of
    /// the reading, s since the start, or the port's failure: when the
    /// servos took it (the earliest of this cycle's fresh readings; each
    /// joint is judged at its own, see [`Tracker::track`]), or now when no
    /// servo answered.
    pub fn read(&mut self) -> Result<f64, PortGone> {
        let read = self.read_feedback();
        self.read_at = self.track.first_fresh().unwrap_or_else(|| self.clock.now());
        read?;
        Ok(self.read_at.saturating_sub(self.start).as_secs_f64())
    }

    fn read_feedback(&mut self) -> Result<(), PortGone> {
        let range = self.plan.reads_in_cycle(self.timing.index);
        if !self.gone && !range.is_empty() {
            // Re-ask missing servos only while the cycle leaves room.
            let budget = (self.timing.deadline + self.period)
                .saturating_sub(self.clock.now())
                .saturating_sub(self.period / 8);
            let servos = range.len();
            // What a perfect adapter would need: the read's fixed cost.
            let model = deadlines::modelled(
                self.bus.settings(),
                self.bus.link(),
                servos,
                self.feedback.size(),
            );
            if self.link.learns() {
                let wait = deadlines::allowance_within(
                    self.bus.settings(),
                    servos,
                    self.feedback.size(),
                    model,
                    budget,
                    self.link.in_force(),
                );
                self.bus.set_latency(wait);
            }
            // The read starts on the wire once this cycle's goals are
            // through the transmitter; measured from the write call, the
            // goals' wire time would pass for the adapter's latency.
            let began = self.bus.line_free();
            let read =
                self.feedback
                    .read(&mut self.bus, &self.clock, range, budget, &mut self.track);
            self.gone = read.is_err();
            if read? {
                let took = self.clock.now().saturating_sub(began);
                self.link.on_time(took.saturating_sub(model));
            } else {
                self.link.timed_out();
            }
            self.bus.set_latency(self.link.in_force());
        }
        Ok(())
    }

    /// Judges the joints against `reference` (robot order, the path at the
    /// time of the reading), learns the lag while a planned path plays
    /// (`main`), and returns the first fault found. `t` is the cycle's time.
    pub fn track(&mut self, reference: &[JointState], main: bool, t: f64) -> Option<Fault> {
        let found = self.track.track(reference, self.read_at);
        for i in 0..self.track.joints.len() {
            let began = self.track.joints.get_mut(i).and_then(|j| {
                let dir = j.press.map(|p| p.dir).filter(|_| j.press_began);
                j.press_began = false;
                dir
            });
            if let Some(dir) = began {
                self.publish_stall(i, true, dir);
            }
        }
        self.lead.learn(self.track.fresh_errors(), main, t);
        found.map(|f| self.fault(f.kind, f.joint, f.reaction))
    }

    /// The fault of a lost port, with the reaction the policy asks of the
    /// other buses.
    pub fn port_gone(&self, e: &PortGone) -> Fault {
        let kind = FaultKind::PortGone {
            message: e.to_string(),
        };
        self.fault(kind, None, self.policy.on_port_gone)
    }

    /// A fault on this bus, for joint `joint` (index in the bus).
    fn fault(&self, kind: FaultKind, joint: Option<usize>, reaction: crate::Reaction) -> Fault {
        let joint = joint.and_then(|i| self.track.joints.get(i));
        Fault {
            kind,
            bus: self.name.clone(),
            joint: joint.map(|j| j.name.clone()),
            servo_id: joint.map(|j| j.id),
            time_s: self.timing.index as f64 * self.period.as_secs_f64(),
            cycle: self.timing.index,
            reaction,
            units: self.units.name(),
        }
    }

    /// Where every joint should hold (its fresh reading, else its last
    /// goal), into `out` (robot order).
    pub fn hold_positions(&self, out: &mut [f64]) {
        let goals = &self.goals.joints;
        let goal = |i: usize| goals.get(i).map_or(0.0, |g| g.rad);
        self.track.hold_positions(self.clock.now(), goal, out);
    }

    /// Disables torque on every servo of the bus, the wheels' goal speed
    /// set to 0 first (no ramp is possible without torque, and a wheel
    /// whose torque comes back on must not turn by itself).
    pub fn torque_off(&mut self) {
        if !self.gone {
            // Nothing more can be done if this fails: the caller ends.
            if self.wheels.any() {
                self.wheels.halt();
                let _ = self.wheels.send_checked(&mut self.bus);
            }
            let _ = self.goals.torque(&mut self.bus, false);
        }
    }

    /// Records the end of the cycle's work and publishes its telemetry.
    pub fn finish_cycle(&mut self, lead: f64) {
        let now = self.clock.now();
        let busy = now.saturating_sub(self.timing.woke);
        self.counters.busy(busy);
        let k = self.timing.index;
        let s = SampleTiming {
            cycle: k,
            time_s: k as f64 * self.period.as_secs_f64(),
            lateness: self.timing.woke.saturating_sub(self.timing.deadline),
            busy,
            skipped: self.timing.skipped,
            lead,
            now,
        };
        self.out
            .cycle(s, &self.goals.joints, &self.wheels, &self.track, self.units);
    }

    /// Sends a message that is not a cycle sample (fault, rejection,
    /// finish); counted as dropped when the channel is full.
    pub fn publish(&mut self, message: Telemetry) {
        self.out.publish(message);
    }
}

/// What the report needs of a bus once its run is over.
impl<T: Transport> BusLoop<T> {
    /// The bus's share of the report, with the lead of its last cycle.
    pub fn outcome(&self) -> Outcome {
        let t = self.timing.index as f64 * self.period.as_secs_f64();
        Outcome {
            index: self.index,
            bus: self.bus_report(),
            joints: self.joint_reports(),
            period_error: self.counters.period_error.clone(),
            span: self.counters.span(),
            cycles: self.counters.cycles,
            dropped: self.out.dropped,
            lead_s: self.lead.at(t),
            lead_identified: self.lead.identified(),
        }
    }

    fn bus_report(&self) -> BusReport {
        let c = self.bus.counters();
        let n = &self.counters;
        let period = self.period.as_secs_f64();
        BusReport {
            name: self.name.clone(),
            cycles: n.cycles,
            overruns: n.overruns,
            utilisation: if n.cycles == 0 {
                0.0
            } else {
                n.busy_total.as_secs_f64() / n.cycles as f64 / period
            },
            peak_utilisation: n.busy_max.as_secs_f64() / period,
            planned_utilisation: self.plan.utilisation(),
            read_every: self.plan.read_every(),
            timeouts: c.timeouts,
            retries: c.retries,
            missed_replies: self.track.missed,
            latency_learned: self.link.learns(),
            startup_probes: self.probe.requests,
            startup_probe_ms: self.probe.took.as_secs_f64() * 1e3,
            latency_us: self.link.mean().as_secs_f64() * 1e6,
            latency_p99_us: self.link.p99().as_secs_f64() * 1e6,
            reply_deadline_us: deadlines::deadline(
                self.bus.settings(),
                self.bus.link(),
                self.feedback.ids().len(),
                self.feedback.size(),
            )
            .as_secs_f64()
                * 1e6,
            eeprom_differences: self.eeprom_differences.clone(),
        }
    }

    /// The joints' tracking figures, in the report's units.
    fn joint_reports(&self) -> Vec<(usize, JointReport)> {
        let u = self.units;
        let goals = self.goals.joints.iter();
        goals
            .zip(&self.track.joints)
            .enumerate()
            .map(|(i, (g, j))| {
                let wheel = self.wheels.of_joint(i);
                let report = JointReport {
                    name: j.name.clone(),
                    rms_error: u.from_rad(j.err.rms()),
                    max_error: u.from_rad(j.err.max_abs()),
                    readings: j.err.count(),
                    clamps: g.clamps,
                    stalls: j.presses,
                    stalled_s: j.pressed_cycles as f64 * self.period.as_secs_f64(),
                    peak_commanded_speed: wheel.map(|w| u.from_rad(w.peak)),
                    peak_measured_speed: wheel.map(|_| u.from_rad(j.peak_speed)),
                };
                (j.robot_index, report)
            })
            .collect()
    }
}

/// The lead estimator of `config`'s position joints (wheels follow no
/// path) at `period`.
fn lead_estimator(lead: Lead, config: &BusConfig, period: Duration) -> LeadEstimator {
    let positions = || config.joints.iter().filter(|j| !j.is_wheel());
    LeadEstimator::new(
        lead,
        lead::prior_lag(
            config.joints.iter().map(|j| j.model.response_lag),
            period.as_secs_f64(),
        ),
        lead::Pace::of(positions().map(|j| (j.max_velocity, j.max_acceleration, j.max_jerk))),
    )
}

/// The goal speed register of a bus's wheels and the present speed read
/// with the position (both `None` on a bus of position joints).
///
/// # Errors
///
/// [`RunError::NoWheelRegisters`] when the series lacks one of them, or the
/// operating mode.
#[allow(clippy::type_complexity)] // two optional registers
fn wheel_registers(
    config: &BusConfig,
    series: Series,
) -> Result<(Option<&'static Register>, Option<&'static Register>), RunError> {
    let Some(wheel) = config.joints.iter().find(|j| j.is_wheel()) else {
        return Ok((None, None));
    };
    let map = series.map();
    let missing = |what| RunError::NoWheelRegisters {
        bus: config.name.clone(),
        joint: wheel.name.clone(),
        series,
        what,
    };
    map.at(addr::MODE)
        .ok_or_else(|| missing("operating mode"))?;
    let goal = map
        .at(addr::GOAL_SPEED)
        .filter(|r| r.is_signed())
        .ok_or_else(|| missing("signed goal speed"))?;
    let present = map
        .at(addr::PRESENT_SPEED)
        .filter(|r| {
            map.at(addr::PRESENT_POSITION)
                .is_some_and(|p| p.end() == u16::from(r.address))
        })
        .ok_or_else(|| missing("present speed after the present position"))?;
    Ok((Some(goal), Some(present)))
}

/// One bus's share of the report.
pub(crate) struct Outcome {
    pub index: usize,
    pub bus: BusReport,
    pub joints: Vec<(usize, JointReport)>,
    pub period_error: Histogram,
    /// `(first woke, last woke, last deadline)` of the cycles run.
    pub span: Option<(Duration, Duration, Duration)>,
    pub cycles: u64,
    pub dropped: u64,
    /// The lead in use at the end, s.
    pub lead_s: f64,
    /// Whether that lead was identified from the run's motion.
    pub lead_identified: bool,
}
