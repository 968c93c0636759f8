//! Running a robot: on simulated buses in virtual time ([`VirtualRun`],
//! deterministic, as fast as the CPU allows) or on any buses on the real
//! clock ([`spawn`], one thread per bus from a shared epoch).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use crossbeam_channel::{bounded, Receiver, Sender, TryRecvError};
use servobus_driver::{Bus, BusSettings, Clock, ManualClock, Transport};
use servobus_protocol::registers::Series;
use servobus_trajectory::{JointState, Trajectory};

use crate::busloop::{BusLoop, CycleTiming, TrackInput};
use crate::command::Command;
use crate::config::{joint_limits, BusConfig, Robot, Units};
use crate::error::RunError;
use crate::fault::{Fault, FaultKind};
use crate::options::{Reaction, RunOptions};
use crate::pacer::Pacer;
use crate::report::{JointReport, Quantiles, Report};
use crate::stats::Histogram;
use crate::telemetry::{Finish, Telemetry};
use crate::timeline::{Kind, Timeline};

/// Joints closer than this to the path's start need no approach, rad.
const APPROACH_TOLERANCE: f64 = 0.5 * std::f64::consts::PI / 180.0;

/// The driver settings of a robot file's bus: the series of its servos,
/// baud rate, adapter latency and return delay.
pub fn bus_settings(config: &BusConfig) -> BusSettings {
    let series = config
        .joints
        .first()
        .map_or(Series::Sts, |j| j.model.series);
    BusSettings::new(series, config.baud)
        .with_latency(config.latency)
        .with_return_delay(config.return_delay)
}

/// What every run shares: validated figures and the channels.
struct Setup {
    rate_hz: f64,
    period: Duration,
    units: Units,
    commands: (Sender<Command>, Receiver<Command>),
    telemetry: (Sender<Telemetry>, Receiver<Telemetry>),
    telemetry_on: bool,
}

fn setup(
    robot: &Robot,
    trajectory: &Trajectory,
    buses: usize,
    o: &RunOptions,
) -> Result<Setup, RunError> {
    let rate_hz = o.rate_hz.unwrap_or(robot.rate_hz);
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(RunError::Invalid(format!(
            "the rate must be positive, got {rate_hz} Hz"
        )));
    }
    if buses != robot.buses.len() {
        return Err(RunError::Invalid(format!(
            "robot `{}` has {} buses, {buses} given",
            robot.name,
            robot.buses.len()
        )));
    }
    if trajectory.joints() != robot.joint_count() {
        return Err(RunError::Invalid(format!(
            "the path has {} joints, robot `{}` {}",
            trajectory.joints(),
            robot.name,
            robot.joint_count()
        )));
    }
    let period = Duration::from_nanos((1e9 / rate_hz).round().max(1.0) as u64);
    Ok(Setup {
        rate_hz,
        period,
        units: o.units.unwrap_or(robot.units),
        commands: bounded(o.command_capacity.max(1)),
        telemetry: bounded(o.telemetry_capacity),
        telemetry_on: o.telemetry_capacity > 0,
    })
}

/// Builds the loops, runs their start-up, and plans the timeline.
fn prepare<T: Transport, C: Clock>(
    robot: &Robot,
    trajectory: Trajectory,
    buses: Vec<Bus<T, C>>,
    o: &RunOptions,
    s: &Setup,
) -> Result<(Vec<BusLoop<T, C>>, Timeline), RunError> {
    let mut loops = Vec::with_capacity(buses.len());
    let mut first = 0;
    for (i, (bus, config)) in buses.into_iter().zip(&robot.buses).enumerate() {
        let tx = s.telemetry_on.then(|| s.telemetry.0.clone());
        let mut l = BusLoop::new(
            i,
            config,
            first,
            robot.units,
            s.units,
            bus,
            s.rate_hz,
            s.period,
            o.faults,
            o.lead,
            tx,
        )?;
        first += config.joints.len();
        l.startup(o.enable_torque)?;
        loops.push(l);
    }
    let mut present = vec![0.0; robot.joint_count()];
    for l in &loops {
        l.present(&mut present);
    }
    let timeline = Timeline::new(
        joint_limits(robot),
        Arc::new(trajectory),
        &present,
        o.approach,
        o.autoplay,
        APPROACH_TOLERANCE,
    )?;
    Ok((loops, timeline))
}

/// One bus's share of cycle `timing.index` at path time `t`: command the
/// path at `t + lead`, read the feedback back, and track it against the
/// path at the time of the reading. Returns the lead used and the fault this
/// cycle raised: a lost port, or what tracking found.
fn bus_cycle<T: Transport, C: Clock>(
    l: &mut BusLoop<T, C>,
    timeline: &mut Timeline,
    cmd: &mut [JointState],
    reference: &mut [JointState],
    timing: CycleTiming,
    t: f64,
) -> (f64, Option<Fault>) {
    l.begin(timing);
    let lead = l.lead_at(t);
    timeline.sample_cmd(t + lead, cmd);
    let mut gone = l.write(cmd).err();
    let x = match l.read() {
        Ok(x) => x,
        Err(msg) => {
            gone.get_or_insert(msg);
            t
        }
    };
    timeline.sample_ref(x, reference);
    let main = matches!(timeline.kind_at(x), Some(Kind::Main | Kind::Approach));
    let found = match gone {
        Some(message) => {
            let reaction = l.policy_port_gone();
            Some(l.fault(FaultKind::PortGone { message }, None, reaction, 0))
        }
        None => l.track(reference, TrackInput { main, t }),
    };
    (lead, found)
}

/// What a command asks of the loops beyond the timeline.
fn apply(timeline: &mut Timeline, command: Command) -> Result<Option<Finish>, String> {
    match command {
        Command::Play => timeline.play(),
        Command::Pause => timeline.set_speed(0.0),
        Command::Resume => timeline.play(),
        Command::Stop => timeline.stop().map_err(|e| e.to_string())?,
        Command::TorqueOff => return Ok(Some(Finish::TorqueOff)),
        Command::Replace(t) => timeline.replace(t).map_err(|e| e.to_string())?,
    }
    Ok(None)
}

/// Why the timeline ended, once it has.
fn finish_of(timeline: &Timeline, fault: bool) -> Finish {
    if fault {
        return Finish::Fault;
    }
    match timeline.last_kind() {
        Some(Kind::Stop) => Finish::Stopped,
        _ => Finish::Completed,
    }
}

/// One bus's share of the report.
struct Outcome {
    index: usize,
    bus: crate::report::BusReport,
    joints: Vec<(usize, JointReport)>,
    period_error: Histogram,
    span: Option<(Duration, Duration, Duration)>,
    cycles: u64,
    dropped: u64,
    lead_s: f64,
}

impl<T: Transport, C: Clock> BusLoop<T, C> {
    fn outcome(&self, t: f64) -> Outcome {
        Outcome {
            index: self.index,
            bus: self.report(),
            joints: self.joint_reports().collect(),
            period_error: self.period_error.clone(),
            span: self.span(),
            cycles: self.cycles,
            dropped: self.dropped,
            lead_s: self.lead_at(t),
        }
    }
}

fn us(d: Duration) -> f64 {
    d.as_secs_f64() * 1e6
}

fn assemble(
    mut outcomes: Vec<Outcome>,
    rate_hz: f64,
    units: Units,
    finish: Finish,
    fault: Option<Fault>,
    warnings: Vec<String>,
) -> Report {
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
        planned_rate_hz: rate_hz,
        period_error_us: Quantiles {
            p50: us(hist.quantile(0.5)),
            p99: us(hist.quantile(0.99)),
            max: us(hist.max()),
        },
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
        units: units.name(),
        joints,
        buses: outcomes.into_iter().map(|o| o.bus).collect(),
        finish,
        fault,
        warnings,
    }
}

/// A run on buses in virtual time, stepped by the caller: deterministic,
/// as fast as the CPU allows. What tests and `servobus play --fast` use.
///
/// Every bus has its own [`ManualClock`] (the one its simulated transport
/// was built with), so that buses model parallel wires: each cycle, every
/// bus's clock is advanced to the same deadline and the bus does its cycle
/// (goals out, feedback in), which moves its clock by the bus time used.
///
/// ```no_run
/// use std::path::Path;
/// use servobus_driver::{Bus, ManualClock};
/// use servobus_runtime::{bus_settings, config, RunOptions, VirtualRun};
/// use servobus_sim::{SimBus, SimServo};
///
/// let (motion, robot) = config::load_motion(Path::new("configs/motions/arm-wave.yaml"), None)?;
/// let path = config::plan_motion(&motion, &robot)?;
/// let buses = robot.buses.iter().map(|b| {
///     let clock = ManualClock::new();
///     let sim = SimBus::new(clock.clone(), b.baud)
///         .with_servos(b.joints.iter().map(|j| SimServo::sts3215(j.id)));
///     Bus::new(sim, clock, bus_settings(b))
/// }).collect();
/// let report = VirtualRun::new(&robot, path, buses, RunOptions::default())?.run();
/// println!("{} cycles at {} Hz", report.cycles, report.achieved_rate_hz);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct VirtualRun<T: Transport> {
    loops: Vec<BusLoop<T, ManualClock>>,
    clocks: Vec<ManualClock>,
    timeline: Timeline,
    commands: Receiver<Command>,
    command_tx: Option<Sender<Command>>,
    telemetry: Receiver<Telemetry>,
    telemetry_on: bool,
    rate_hz: f64,
    period: Duration,
    start: Duration,
    units: Units,
    settle: f64,
    next: u64,
    cmd: Vec<JointState>,
    reference: Vec<JointState>,
    hold: Vec<f64>,
    fault: Option<Fault>,
    finish: Option<Finish>,
}

impl<T: Transport> VirtualRun<T> {
    /// Prepares a run of `trajectory` (robot joint order, radians) on
    /// `buses` (one per robot bus, in order, each with its own
    /// [`ManualClock`]): reads every servo's position, enables torque and
    /// plans the approach to the path's start.
    ///
    /// # Errors
    ///
    /// [`RunError::Invalid`] when the buses or the path do not match the
    /// robot, [`RunError::Plan`] when the rate does not fit a bus,
    /// [`RunError::NoServo`] / [`RunError::Startup`] when a servo does not
    /// answer at start-up, [`RunError::Trajectory`] when the approach
    /// cannot be planned.
    pub fn new(
        robot: &Robot,
        trajectory: Trajectory,
        buses: Vec<Bus<T, ManualClock>>,
        options: RunOptions,
    ) -> Result<Self, RunError> {
        let s = setup(robot, &trajectory, buses.len(), &options)?;
        let clocks: Vec<ManualClock> = buses.iter().map(|b| b.clock().clone()).collect();
        let (mut loops, timeline) = prepare(robot, trajectory, buses, &options, &s)?;
        // Cycle 0 starts one period after the slowest bus's start-up.
        let start = clocks.iter().map(Clock::now).max().unwrap_or_default() + s.period;
        for l in &mut loops {
            l.start = start;
        }
        let n = robot.joint_count();
        Ok(VirtualRun {
            loops,
            clocks,
            timeline,
            commands: s.commands.1,
            command_tx: Some(s.commands.0),
            telemetry: s.telemetry.1,
            telemetry_on: s.telemetry_on,
            rate_hz: s.rate_hz,
            period: s.period,
            start,
            units: s.units,
            settle: options.settle.as_secs_f64(),
            next: 0,
            cmd: vec![JointState::default(); n],
            reference: vec![JointState::default(); n],
            hold: vec![0.0; n],
            fault: None,
            finish: None,
        })
    }

    /// A sender of commands; they take effect at the next [`step`](Self::step).
    pub fn commands(&self) -> Sender<Command> {
        match &self.command_tx {
            Some(tx) => tx.clone(),
            None => bounded(1).0,
        }
    }

    /// A receiver of telemetry (empty when
    /// [`RunOptions::telemetry_capacity`] is 0).
    pub fn telemetry(&self) -> Receiver<Telemetry> {
        self.telemetry.clone()
    }

    /// The bus at `index`, to inspect its counters or transport.
    pub fn bus(&self, index: usize) -> Option<&Bus<T, ManualClock>> {
        self.loops.get(index).map(|l| &l.bus)
    }

    /// The next cycle's number.
    pub fn cycle(&self) -> u64 {
        self.next
    }

    /// The period.
    pub fn period(&self) -> Duration {
        self.period
    }

    /// The clock time of cycle 0 (on every bus's clock).
    pub fn start(&self) -> Duration {
        self.start
    }

    /// Why the run ended, once it has.
    pub fn finished(&self) -> Option<Finish> {
        self.finish
    }

    /// The fault detected, if any.
    pub fn fault(&self) -> Option<&Fault> {
        self.fault.as_ref()
    }

    fn react(&mut self, fault: Fault, from: usize) {
        if self.fault.is_some() {
            return;
        }
        if let Some(l) = self.loops.get_mut(from) {
            l.publish(Telemetry::Fault(fault.clone()));
        }
        let reaction = fault.reaction;
        self.fault = Some(fault);
        match reaction {
            Reaction::Stop => {
                if self.timeline.stop().is_err() {
                    self.react_hold();
                }
            }
            Reaction::Hold => self.react_hold(),
            Reaction::TorqueOff => {
                for l in &mut self.loops {
                    l.torque_off();
                }
                self.finish = Some(Finish::Fault);
            }
        }
    }

    fn react_hold(&mut self) {
        for l in &self.loops {
            l.hold_positions(&mut self.hold);
        }
        self.timeline.hold(self.hold.clone());
        for l in &mut self.loops {
            let _ = l.send_hold(&self.hold);
        }
    }

    /// Runs one cycle on every bus. Returns false once the run has ended
    /// (the path completed, a stop or fault reaction finished, torque was
    /// turned off); later calls do nothing.
    pub fn step(&mut self) -> bool {
        if self.finish.is_some() {
            return false;
        }
        let k = self.next;
        self.next += 1;
        let t = k as f64 * self.period.as_secs_f64();
        let deadline = self.start + self.period * u32::try_from(k).unwrap_or(u32::MAX);
        loop {
            match self.commands.try_recv() {
                Ok(c) => match apply(&mut self.timeline, c) {
                    Ok(Some(finish)) => {
                        for l in &mut self.loops {
                            l.torque_off();
                        }
                        self.finish = Some(finish);
                        return false;
                    }
                    Ok(None) => {}
                    Err(why) => {
                        if let Some(l) = self.loops.first_mut() {
                            l.publish(Telemetry::Rejected(why));
                        }
                    }
                },
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    if self.timeline.last_kind() == Some(Kind::Hold { last: false }) {
                        self.finish = Some(Finish::Abandoned);
                        return false;
                    }
                    break;
                }
            }
        }
        for b in 0..self.loops.len() {
            let clock = &self.clocks[b];
            if clock.now() >= deadline + self.period {
                // Still busy with an earlier cycle: this deadline is skipped
                // (counted as an overrun at the bus's next cycle).
                continue;
            }
            clock.advance_to(deadline);
            let woke = clock.now();
            let l = &mut self.loops[b];
            let timing = CycleTiming {
                index: k,
                deadline,
                woke,
                skipped: 0,
            };
            let (lead, found) = bus_cycle(
                l,
                &mut self.timeline,
                &mut self.cmd,
                &mut self.reference,
                timing,
                t,
            );
            if let Some(f) = found {
                self.react(f, b);
            }
            self.loops[b].finish_cycle(lead);
        }
        self.timeline.prune(t);
        if self.finish.is_none() && self.timeline.finished(t, self.settle) {
            self.finish = Some(finish_of(&self.timeline, self.fault.is_some()));
        }
        self.finish.is_none()
    }

    /// The report so far.
    pub fn report(&self) -> Report {
        let t = self.next as f64 * self.period.as_secs_f64();
        assemble(
            self.loops.iter().map(|l| l.outcome(t)).collect(),
            self.rate_hz,
            self.units,
            self.finish.unwrap_or(Finish::Completed),
            self.fault.clone(),
            Vec::new(),
        )
    }

    /// Steps to the end of the run, publishes
    /// [`Telemetry::Finished`], and returns the report. A run waiting for
    /// [`Command::Play`] ends as [`Finish::Abandoned`] once every other
    /// command sender is gone.
    pub fn run(mut self) -> Report {
        self.command_tx = None;
        while self.step() {}
        let finish = self.finish.unwrap_or(Finish::Completed);
        if self.telemetry_on {
            if let Some(l) = self.loops.first_mut() {
                l.publish(Telemetry::Finished(finish));
            }
        }
        self.report()
    }
}

/// A run in progress on its own threads.
///
/// The telemetry channel disconnects once the run has ended and every
/// message has been read.
#[derive(Debug)]
pub struct Runner {
    commands: Sender<Command>,
    telemetry: Receiver<Telemetry>,
    handle: JoinHandle<Result<Report, RunError>>,
}

impl Runner {
    /// A sender of commands.
    pub fn commands(&self) -> Sender<Command> {
        self.commands.clone()
    }

    /// Sends a command (waits if the command channel is full).
    ///
    /// # Errors
    ///
    /// [`RunError::Thread`] when the run has already ended.
    pub fn send(&self, command: Command) -> Result<(), RunError> {
        self.commands
            .send(command)
            .map_err(|_| RunError::Thread("the run has ended".into()))
    }

    /// A receiver of telemetry.
    pub fn telemetry(&self) -> Receiver<Telemetry> {
        self.telemetry.clone()
    }

    /// Whether the run has ended.
    pub fn is_finished(&self) -> bool {
        self.handle.is_finished()
    }

    /// Waits for the end of the run and returns its report.
    ///
    /// # Errors
    ///
    /// [`RunError::Thread`] when a bus thread panicked.
    pub fn join(self) -> Result<Report, RunError> {
        drop(self.commands);
        self.handle
            .join()
            .map_err(|_| RunError::Thread("the run's thread panicked".into()))?
    }
}

/// Runs a [`VirtualRun`] on a thread of its own (for `servobus play --fast`
/// with a progress bar reading the telemetry).
///
/// # Errors
///
/// As [`VirtualRun::new`].
pub fn spawn_virtual<T: Transport + Send + 'static>(
    robot: &Robot,
    trajectory: Trajectory,
    buses: Vec<Bus<T, ManualClock>>,
    options: RunOptions,
) -> Result<Runner, RunError> {
    let run = VirtualRun::new(robot, trajectory, buses, options)?;
    let commands = run.commands();
    let telemetry = run.telemetry();
    let handle = std::thread::Builder::new()
        .name("servobus-virtual".into())
        .spawn(move || Ok(run.run()))
        .map_err(|e| RunError::Thread(e.to_string()))?;
    Ok(Runner {
        commands,
        telemetry,
        handle,
    })
}

/// The fault every bus thread shares: the first one wins.
#[derive(Default)]
struct Shared {
    raised: AtomicBool,
    fault: Mutex<Option<Fault>>,
    warnings: Mutex<Vec<String>>,
}

impl Shared {
    fn raise(&self, f: &Fault) -> bool {
        let mut slot = self.fault.lock().unwrap_or_else(|e| e.into_inner());
        if slot.is_some() {
            return false;
        }
        *slot = Some(f.clone());
        self.raised.store(true, Ordering::Release);
        true
    }
    fn get(&self) -> Option<Fault> {
        if !self.raised.load(Ordering::Acquire) {
            return None;
        }
        self.fault.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

/// Commands stamped with the cycle they take effect in on every bus.
type Stamped = (u64, Command);

/// How many cycles ahead a command is stamped, so that every bus thread
/// has received it before its cycle comes.
const COMMAND_DELAY_CYCLES: u64 = 2;

/// Runs `trajectory` on `buses` (one per robot bus, in order) on the clock
/// they were built with, one thread per bus, in step from a shared epoch:
/// cycle `k` of every bus is due at `start + k * period`.
///
/// The buses' clocks must share their time base (clones of one
/// [`SystemClock`](servobus_driver::SystemClock)). Start-up (reading
/// positions, enabling torque, planning the approach) happens before this
/// returns; the first cycle is due 50 ms (at least 5 periods) later. Each
/// thread keeps its own copy of the robot-wide path, and commands take
/// effect in the same cycle on every bus.
///
/// # Errors
///
/// As [`VirtualRun::new`]; [`RunError::Thread`] when a thread cannot start.
pub fn spawn<T, C>(
    robot: &Robot,
    trajectory: Trajectory,
    buses: Vec<Bus<T, C>>,
    options: RunOptions,
) -> Result<Runner, RunError>
where
    T: Transport + Send + 'static,
    C: Clock,
{
    let s = setup(robot, &trajectory, buses.len(), &options)?;
    let Some(clock) = buses.first().map(|b| b.clock().clone()) else {
        return Err(RunError::Invalid("no bus given".into()));
    };
    let (loops, timeline) = prepare(robot, trajectory, buses, &options, &s)?;
    let start = clock.now() + (s.period * 5).max(Duration::from_millis(50));
    let shared = Arc::new(Shared::default());
    let n = robot.joint_count();
    let mut forwards: Vec<Sender<Stamped>> = Vec::new();
    let mut inboxes: Vec<Option<Receiver<Stamped>>> = vec![None];
    for _ in 1..loops.len() {
        let (tx, rx) = bounded(options.command_capacity.max(1) * 2);
        forwards.push(tx);
        inboxes.push(Some(rx));
    }
    let mut threads = Vec::with_capacity(loops.len());
    for (mut l, inbox) in loops.into_iter().zip(inboxes) {
        l.start = start;
        let mut worker = Worker {
            timeline: timeline.clone(),
            user: (l.index == 0).then(|| s.commands.1.clone()),
            forwards: if l.index == 0 {
                forwards.clone()
            } else {
                Vec::new()
            },
            inbox,
            pending: Vec::with_capacity(16),
            shared: Arc::clone(&shared),
            cmd: vec![JointState::default(); n],
            reference: vec![JointState::default(); n],
            hold: vec![0.0; n],
            fault: None,
            settle: options.settle.as_secs_f64(),
            period: s.period,
        };
        let rt = crate::rt::RtOptions {
            core: options.rt.core.map(|c| c + l.index),
            fifo_priority: options.rt.fifo_priority,
        };
        let spin = options.spin;
        let name = format!("servobus-{}", l.name);
        let handle = std::thread::Builder::new()
            .name(name)
            .spawn(move || {
                let report = crate::rt::apply(rt);
                if !report.warnings.is_empty() {
                    let mut w = worker
                        .shared
                        .warnings
                        .lock()
                        .unwrap_or_else(|e| e.into_inner());
                    w.extend(report.warnings);
                }
                let clock = l.bus.clock().clone();
                let mut pacer = Pacer::new(clock, start, worker.period).with_spin(spin);
                let finish = loop {
                    let tick = pacer.wait();
                    if let Some(f) = worker.cycle(&mut l, tick.index, tick.deadline, tick.woke) {
                        break f;
                    }
                };
                if l.index == 0 {
                    l.publish(Telemetry::Finished(finish));
                }
                (l.outcome(f64::INFINITY), finish)
            })
            .map_err(|e| RunError::Thread(e.to_string()))?;
        threads.push(handle);
    }
    drop(forwards);
    let rate_hz = s.rate_hz;
    let units = s.units;
    let supervisor = std::thread::Builder::new()
        .name("servobus-run".into())
        .spawn(move || {
            let mut outcomes = Vec::new();
            let mut finish = Finish::Completed;
            for t in threads {
                let (o, f) = t
                    .join()
                    .map_err(|_| RunError::Thread("a bus thread panicked".into()))?;
                if o.index == 0 || f == Finish::Fault {
                    finish = f;
                }
                outcomes.push(o);
            }
            let fault = shared.get();
            let warnings = shared
                .warnings
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .clone();
            Ok(assemble(outcomes, rate_hz, units, finish, fault, warnings))
        })
        .map_err(|e| RunError::Thread(e.to_string()))?;
    Ok(Runner {
        commands: s.commands.0,
        telemetry: s.telemetry.1,
        handle: supervisor,
    })
}

/// One bus thread's copy of the run.
struct Worker {
    timeline: Timeline,
    /// The user's command channel (bus 0 only).
    user: Option<Receiver<Command>>,
    /// Where bus 0 forwards stamped commands.
    forwards: Vec<Sender<Stamped>>,
    /// Stamped commands from bus 0 (other buses).
    inbox: Option<Receiver<Stamped>>,
    pending: Vec<Stamped>,
    shared: Arc<Shared>,
    cmd: Vec<JointState>,
    reference: Vec<JointState>,
    hold: Vec<f64>,
    fault: Option<Reaction>,
    settle: f64,
    period: Duration,
}

impl Worker {
    fn react<T: Transport, C: Clock>(
        &mut self,
        l: &mut BusLoop<T, C>,
        reaction: Reaction,
    ) -> Option<Finish> {
        if self.fault.is_some() {
            return None;
        }
        self.fault = Some(reaction);
        match reaction {
            Reaction::Stop => {
                if self.timeline.stop().is_ok() {
                    return None;
                }
                self.hold_here(l);
                None
            }
            Reaction::Hold => {
                self.hold_here(l);
                None
            }
            Reaction::TorqueOff => {
                l.torque_off();
                Some(Finish::Fault)
            }
        }
    }

    fn hold_here<T: Transport, C: Clock>(&mut self, l: &mut BusLoop<T, C>) {
        // Joints of other buses keep their commanded position in this copy
        // of the path; only this bus's joints are sent from it.
        let x = self.timeline.horizon();
        self.timeline.sample_ref(x, &mut self.cmd);
        for (h, c) in self.hold.iter_mut().zip(&self.cmd) {
            *h = c.position;
        }
        l.hold_positions(&mut self.hold);
        self.timeline.hold(self.hold.clone());
        let _ = l.send_hold(&self.hold);
    }

    /// One cycle; `Some` once the run has ended for this bus.
    fn cycle<T: Transport, C: Clock>(
        &mut self,
        l: &mut BusLoop<T, C>,
        k: u64,
        deadline: Duration,
        woke: Duration,
    ) -> Option<Finish> {
        let t = k as f64 * self.period.as_secs_f64();
        if let Some(user) = &self.user {
            while let Ok(c) = user.try_recv() {
                let stamp = k + COMMAND_DELAY_CYCLES;
                for f in &self.forwards {
                    let _ = f.try_send((stamp, c.clone()));
                }
                self.pending.push((stamp, c));
            }
        }
        if let Some(inbox) = &self.inbox {
            while let Ok(sc) = inbox.try_recv() {
                self.pending.push(sc);
            }
        }
        while let Some(i) = self.pending.iter().position(|(s, _)| *s <= k) {
            let (_, c) = self.pending.remove(i);
            match apply(&mut self.timeline, c) {
                Ok(Some(finish)) => {
                    l.torque_off();
                    return Some(finish);
                }
                Ok(None) => {}
                Err(why) => l.publish(Telemetry::Rejected(why)),
            }
        }
        if self.fault.is_none() {
            if let Some(f) = self.shared.get() {
                if let Some(finish) = self.react(l, f.reaction) {
                    return Some(finish);
                }
            }
        }
        let timing = CycleTiming {
            index: k,
            deadline,
            woke,
            skipped: 0,
        };
        let (lead, found) = bus_cycle(
            l,
            &mut self.timeline,
            &mut self.cmd,
            &mut self.reference,
            timing,
            t,
        );
        let mut end = None;
        if let Some(f) = found {
            if self.fault.is_none() && self.shared.raise(&f) {
                l.publish(Telemetry::Fault(f.clone()));
            }
            end = self.react(l, f.reaction);
        }
        l.finish_cycle(lead);
        if end.is_some() {
            return end;
        }
        self.timeline.prune(t);
        if self.timeline.finished(t, self.settle) {
            return Some(finish_of(&self.timeline, self.fault.is_some()));
        }
        None
    }
}
