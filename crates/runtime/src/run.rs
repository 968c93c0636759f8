//! What both ways of running a robot share: checking the robot, buses and
//! path against each other, start-up, the lanes (one per bus, see
//! [`crate::lane`]) with their first cycle's time, and the report.
//!
//! [`VirtualRun`](crate::VirtualRun) steps the lanes one after the other on
//! simulated buses in virtual time; [`spawn`](crate::spawn) runs each on its
//! own thread on the buses' clock. Both are built here, by [`prepare`].

use std::sync::Arc;
use std::time::Duration;

use crossbeam_channel::{bounded, Receiver, Sender};
use servobus_driver::{Bus, BusSettings, Clock, Transport};
use servobus_protocol::registers::Series;
use servobus_trajectory::{JointLimits, Trajectory};

use crate::busloop::{reachable, BusLoop, LoopConfig, Outcome};
use crate::config::{joint_limits, BusConfig, Robot, Units};
use crate::error::RunError;
use crate::exchange::{inboxes, CommandSender, FaultBoard, Mailbox};
use crate::fault::Fault;
use crate::lane::Lane;
use crate::options::RunOptions;
use crate::report::{JointReport, Quantiles, Report};
use crate::stats::Histogram;
use crate::target::{LiveReport, TargetCounts, TargetSender};
use crate::telemetry::{Finish, Telemetry};
use crate::timeline::Timeline;

/// Joints closer than this to the path's start need no approach, rad.
const APPROACH_TOLERANCE: f64 = 0.5 * std::f64::consts::PI / 180.0;

/// The first cycle is due this long after start-up at least (and at least
/// five periods): on the real clock, time for every bus thread to start
/// and settle; in virtual time it costs nothing.
const START_GAP: Duration = Duration::from_millis(50);

/// The driver settings of a robot file's bus: the series of its servos,
/// baud rate, adapter latency and return delay.
pub fn bus_settings(config: &BusConfig) -> BusSettings {
    let series = config
        .joints
        .first()
        .map_or(Series::Sts, |j| j.model.series);
    BusSettings::new(series)
        .with_latency(config.latency)
        .with_return_delay(config.return_delay)
}

/// A run ready for its first cycle.
pub(crate) struct Prepared<T: Transport> {
    pub lanes: Vec<Lane<T>>,
    /// Clock time of cycle 0, on every bus's clock.
    pub start: Duration,
    pub period: Duration,
    pub rate_hz: f64,
    /// The report's units.
    pub units: Units,
    pub board: Arc<FaultBoard>,
    pub commands: CommandSender,
    pub telemetry: Receiver<Telemetry>,
    /// For the end-of-run message (`None` without telemetry).
    pub telemetry_tx: Option<Sender<Telemetry>>,
    /// The approach to the path's start, as the timeline planned it.
    pub approach: Duration,
    /// The sender of live targets.
    pub targets: TargetSender,
    /// The counts of live targets, for the report.
    pub counters: Arc<TargetCounts>,
}

/// Checks the robot, buses and path against each other and `o`. Returns
/// the rate and the period.
fn check(
    robot: &Robot,
    trajectory: Option<&Trajectory>,
    buses: usize,
    o: &RunOptions,
) -> Result<(f64, Duration), RunError> {
    let rate_hz = o.rate_hz.unwrap_or(robot.rate_hz);
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(RunError::Rate { rate_hz });
    }
    if buses == 0 || buses != robot.buses.len() {
        return Err(RunError::BusCount {
            robot: robot.name.clone(),
            expected: robot.buses.len(),
            given: buses,
        });
    }
    if let Some(trajectory) = trajectory.filter(|t| t.joints() != robot.joint_count()) {
        return Err(RunError::JointCount {
            robot: robot.name.clone(),
            expected: robot.joint_count(),
            given: trajectory.joints(),
        });
    }
    let timeout = o.target_timeout.as_secs_f64();
    if timeout.is_nan() || timeout <= 0.0 {
        return Err(RunError::TargetTimeout);
    }
    let period = Duration::from_nanos((1e9 / rate_hz).round().max(1.0) as u64);
    Ok((rate_hz, period))
}

/// Builds the loops, runs their start-up, plans the timeline (`None`: no
/// path, hold and follow live targets), and wires the lanes: the first
/// receives the user's commands and targets and forwards them.
pub(crate) fn prepare<T: Transport>(
    robot: &Robot,
    trajectory: Option<Trajectory>,
    buses: Vec<Bus<T>>,
    o: &RunOptions,
) -> Result<Prepared<T>, RunError> {
    let (rate_hz, period) = check(robot, trajectory.as_ref(), buses.len(), o)?;
    let units = o.units.unwrap_or(robot.units);
    let (telemetry_tx, telemetry) = bounded(o.telemetry_capacity);
    let telemetry_tx = (o.telemetry_capacity > 0).then_some(telemetry_tx);
    let figures = Figures {
        rate_hz,
        period,
        units,
    };
    let loops = start_buses(robot, buses, o, figures, &telemetry_tx)?;
    let mut present = vec![0.0; robot.joint_count()];
    for l in &loops {
        l.present(&mut present);
    }
    let plain = joint_limits(robot);
    let limits = live_limits(robot, &plain);
    let live_session = trajectory.is_none();
    let mut timeline = plan_timeline(trajectory, plain, limits.clone(), &present, o)?;
    timeline.set_wheels(robot.joints().map(|j| j.is_wheel()).collect());
    let approach = timeline.approach();
    // Cycle 0 is due a gap after the slowest bus's start-up.
    let last = loops.iter().map(|l| l.bus.clock().now()).max();
    let start = last.unwrap_or_default() + (period * 5).max(START_GAP);
    let (commands, target_tx, inboxes) =
        inboxes(loops.len(), o.command_capacity, o.target_capacity);
    let names: Vec<String> = robot.joints().map(|j| j.name.clone()).collect();
    let counters = Arc::new(TargetCounts::new(names.clone(), units));
    if live_session {
        counters.live_session();
    }
    let targets = TargetSender::new(target_tx, names, limits, Arc::clone(&counters));
    let board = Arc::new(FaultBoard::default());
    let lanes = loops
        .into_iter()
        .zip(inboxes)
        .map(|(mut l, inbox)| {
            l.start = start;
            let mail = Mailbox::new(inbox);
            let b = Arc::clone(&board);
            let c = Arc::clone(&counters);
            let n = robot.joint_count();
            Lane::new(l, timeline.clone(), mail, b, c, n, o.settle, period)
        })
        .collect();
    Ok(Prepared {
        lanes,
        start,
        period,
        rate_hz,
        units,
        board,
        commands,
        telemetry,
        telemetry_tx,
        approach,
        targets,
        counters,
    })
}

/// The limits live targets are kept within: the ticks inside each joint's
/// limits, where goals are sent as they are; for a wheel, whose target is a
/// speed, its top speed either way (`+-max_velocity`, rad/s), so that a
/// faster target is clamped and counted as a position beyond a limit is.
fn live_limits(robot: &Robot, plain: &[JointLimits]) -> Vec<JointLimits> {
    plain
        .iter()
        .zip(robot.joints())
        .map(|(l, j)| {
            if j.is_wheel() {
                let top = l.max_velocity.abs();
                return l.with_positions(-top, top);
            }
            let (lo, hi) = reachable(j, robot.units);
            l.with_positions(lo.max(l.min_position), hi.min(l.max_position))
        })
        .collect()
}

/// The timeline from `present`: the path with its approach, or (no path)
/// live following from the start; live targets are followed within `limits`.
fn plan_timeline(
    trajectory: Option<Trajectory>,
    plain: Vec<JointLimits>,
    limits: Vec<JointLimits>,
    present: &[f64],
    o: &RunOptions,
) -> Result<Timeline, RunError> {
    let timeout = o.target_timeout.as_secs_f64();
    let mut timeline = match trajectory {
        Some(trajectory) => Timeline::new(
            plain,
            Arc::new(trajectory),
            present,
            o.approach,
            o.autoplay,
            APPROACH_TOLERANCE,
        )?,
        None => Timeline::live(limits.clone(), present, timeout),
    };
    timeline.set_live(timeout, limits);
    timeline.set_grasps(o.grasps.clone());
    Ok(timeline)
}

/// The run's figures every bus loop is built with.
#[derive(Clone, Copy)]
struct Figures {
    rate_hz: f64,
    period: Duration,
    /// The report's units.
    units: Units,
}

/// Builds every bus's loop and runs its start-up.
fn start_buses<T: Transport>(
    robot: &Robot,
    buses: Vec<Bus<T>>,
    o: &RunOptions,
    f: Figures,
    telemetry: &Option<Sender<Telemetry>>,
) -> Result<Vec<BusLoop<T>>, RunError> {
    let mut loops = Vec::with_capacity(buses.len());
    let mut first_joint = 0;
    for (index, (bus, config)) in buses.into_iter().zip(&robot.buses).enumerate() {
        let c = LoopConfig {
            index,
            bus: config,
            first_joint,
            units: robot.units,
            report_units: f.units,
            rate_hz: f.rate_hz,
            period: f.period,
            policy: o.faults,
            lead: o.lead,
            telemetry: telemetry.clone(),
        };
        let mut l = BusLoop::new(c, bus)?;
        first_joint += config.joints.len();
        l.startup(o.enable_torque)?;
        loops.push(l);
    }
    Ok(loops)
}

/// What a finished run adds to its lanes' outcomes.
pub(crate) struct Ending {
    pub rate_hz: f64,
    pub units: Units,
    pub finish: Finish,
    pub fault: Option<Fault>,
    pub warnings: Vec<String>,
    pub live: Option<LiveReport>,
}

fn us(d: Duration) -> f64 {
    d.as_secs_f64() * 1e6
}

/// The report of a run from its lanes' outcomes.
pub(crate) fn assemble(mut outcomes: Vec<Outcome>, e: Ending) -> Report {
    outcomes.sort_by_key(|o| o.index);
    let mut hist = Histogram::new(Duration::from_millis(100));
    let mut joints: Vec<(usize, JointReport)> = Vec::new();
    for o in &outcomes {
        hist.merge(&o.period_error);
        joints.extend(o.joints.iter().cloned());
    }
    joints.sort_by_key(|(i, _)| *i);
    let first = outcomes.first();
    let (achieved, duration, drift) = match first.and_then(|o| o.span.map(|s| (o.cycles, s))) {
        Some((cycles, (first, last, deadline))) if cycles > 1 && last > first => {
            let nanos = (last - first).as_nanos() as f64;
            (
                (cycles - 1) as f64 * 1e9 / nanos,
                (last - first).as_secs_f64(),
                us(last.saturating_sub(deadline)),
            )
        }
        _ => (0.0, 0.0, 0.0),
    };
    let sum = |f: fn(&Outcome) -> u64| outcomes.iter().map(f).sum::<u64>();
    let joints: Vec<JointReport> = joints.into_iter().map(|(_, j)| j).collect();
    Report {
        cycles: first.map_or(0, |o| o.cycles),
        achieved_rate_hz: achieved,
        planned_rate_hz: e.rate_hz,
        period_error_us: Quantiles::of(&hist, Duration::from_micros(1)),
        overruns: sum(|o| o.bus.overruns),
        timeouts: sum(|o| o.bus.timeouts),
        retries: sum(|o| o.bus.retries),
        missed_replies: sum(|o| o.bus.missed_replies),
        clamps: joints.iter().map(|j| j.clamps).sum(),
        telemetry_dropped: sum(|o| o.dropped),
        utilisation: outcomes
            .iter()
            .map(|o| o.bus.utilisation)
            .fold(0.0, f64::max),
        duration_s: duration,
        drift_us: drift,
        lead_ms: first.map_or(0.0, |o| o.lead_s * 1e3),
        lead_identified: first.is_some_and(|o| o.lead_identified),
        units: e.units.name(),
        joints,
        buses: outcomes.into_iter().map(|o| o.bus).collect(),
        finish: e.finish,
        fault: e.fault,
        warnings: e.warnings,
        live: e.live,
    }
}
