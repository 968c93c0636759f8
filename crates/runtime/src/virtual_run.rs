//! Running a robot in virtual time: the lanes stepped one after the other,
//! each on its own simulated bus and [`ManualClock`], paced by the same
//! [`Pacer`] the bus threads use.

use std::sync::Arc;
use std::time::Duration;

use crossbeam_channel::Receiver;
use servobus_driver::{Bus, ManualClock, Transport};
use servobus_trajectory::Trajectory;

use crate::config::{Robot, Units};
use crate::error::RunError;
use crate::exchange::{CommandSender, FaultBoard};
use crate::fault::Fault;
use crate::lane::{overall, Lane};
use crate::options::RunOptions;
use crate::pacer::Pacer;
use crate::report::Report;
use crate::run::{assemble, prepare, Ending};
use crate::target::{TargetCounts, TargetSender};
use crate::telemetry::{Finish, Telemetry};

/// A run on buses in virtual time, stepped by the caller: deterministic,
/// as fast as the CPU allows. What tests and `servobus play --fast` use.
///
/// It runs the very cycle function the bus threads of [`spawn`](crate::spawn)
/// run (commands, fault reactions, holds and stops included); only the
/// clock and the pacing differ. Every bus has its own [`ManualClock`] (the
/// one its simulated transport was built with), so that buses model
/// parallel wires: each step, every bus's [`Pacer`] advances its clock to
/// the cycle's deadline and the bus does its cycle (goals out, feedback
/// in), which moves its clock by the bus time used.
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
///     Bus::new(sim, bus_settings(b))
/// }).collect();
/// let report = VirtualRun::new(&robot, path, buses, RunOptions::default())?.run();
/// println!("{} cycles at {} Hz", report.cycles, report.achieved_rate_hz);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct VirtualRun<T: Transport<Clock = ManualClock>> {
    lanes: Vec<Lane<T>>,
    pacers: Vec<Pacer<ManualClock>>,
    board: Arc<FaultBoard>,
    command_tx: Option<CommandSender>,
    targets: TargetSender,
    counters: Arc<TargetCounts>,
    telemetry: Receiver<Telemetry>,
    telemetry_tx: Option<crossbeam_channel::Sender<Telemetry>>,
    rate_hz: f64,
    period: Duration,
    start: Duration,
    units: Units,
    /// The approach to the path's start, as planned.
    approach: Duration,
    next: u64,
    /// The first fault, once the board has one (kept to lend it out).
    fault: Option<Fault>,
    finish: Option<Finish>,
}

impl<T: Transport<Clock = ManualClock>> VirtualRun<T> {
    /// Prepares a run of `trajectory` (robot joint order, radians) on
    /// `buses` (one per robot bus, in order, each with its own
    /// [`ManualClock`]): reads every servo's position, enables torque and
    /// plans the approach to the path's start.
    ///
    /// # Errors
    ///
    /// [`RunError::BusCount`] or [`RunError::JointCount`] when the buses or the path do not match the
    /// robot, [`RunError::Plan`] when the rate does not fit a bus,
    /// [`RunError::NoServo`] / [`RunError::Startup`] when a servo does not
    /// answer at start-up, [`RunError::Trajectory`] when the approach
    /// cannot be planned.
    pub fn new(
        robot: &Robot,
        trajectory: Trajectory,
        buses: Vec<Bus<T>>,
        options: RunOptions,
    ) -> Result<Self, RunError> {
        Self::prepared(robot, Some(trajectory), buses, options)
    }

    /// Prepares a run with no path: the joints hold where they are read at
    /// start-up and follow the live targets sent through
    /// [`targets`](Self::targets), each cycle a jerk-limited step toward
    /// the newest (see [`LiveTarget`](crate::LiveTarget)). No target for
    /// [`RunOptions::target_timeout`]: a jerk-limited stop and hold; the
    /// next target resumes. The run ends on [`Command::Stop`](crate::Command::Stop),
    /// [`Command::TorqueOff`](crate::Command::TorqueOff) or a fault.
    ///
    /// # Errors
    ///
    /// As [`new`](Self::new).
    pub fn live(robot: &Robot, buses: Vec<Bus<T>>, options: RunOptions) -> Result<Self, RunError> {
        Self::prepared(robot, None, buses, options)
    }

    fn prepared(
        robot: &Robot,
        trajectory: Option<Trajectory>,
        buses: Vec<Bus<T>>,
        options: RunOptions,
    ) -> Result<Self, RunError> {
        let p = prepare(robot, trajectory, buses, &options)?;
        // No spinning: a virtual clock only moves when slept on.
        let pacers = p
            .lanes
            .iter()
            .map(|l| Pacer::new(l.bus.bus.clock().clone(), p.start, p.period))
            .collect();
        Ok(VirtualRun {
            lanes: p.lanes,
            pacers,
            board: p.board,
            command_tx: Some(p.commands),
            targets: p.targets,
            counters: p.counters,
            telemetry: p.telemetry,
            telemetry_tx: p.telemetry_tx,
            rate_hz: p.rate_hz,
            period: p.period,
            start: p.start,
            units: p.units,
            approach: p.approach,
            next: 0,
            fault: None,
            finish: None,
        })
    }

    /// A sender of commands. A command received in a step takes effect
    /// [`COMMAND_DELAY_CYCLES`](crate::COMMAND_DELAY_CYCLES) cycles later
    /// (as on threads), or at the cycle given to
    /// [`CommandSender::send_at`].
    pub fn commands(&self) -> CommandSender {
        match &self.command_tx {
            Some(tx) => tx.clone(),
            None => CommandSender::new(crossbeam_channel::bounded(1).0),
        }
    }

    /// A sender of live targets. A target received in a step takes effect
    /// in that step's cycle on a robot of one bus,
    /// [`COMMAND_DELAY_CYCLES`](crate::COMMAND_DELAY_CYCLES) later on
    /// several; a run playing a path switches to following at the first.
    pub fn targets(&self) -> TargetSender {
        self.targets.clone()
    }

    /// A receiver of telemetry (empty when
    /// [`RunOptions::telemetry_capacity`] is 0).
    pub fn telemetry(&self) -> Receiver<Telemetry> {
        self.telemetry.clone()
    }

    /// How long the approach to the path's start takes, as planned from
    /// the positions read at start-up (zero when the joints were there
    /// already): the path begins that long after cycle 0.
    pub fn approach(&self) -> Duration {
        self.approach
    }

    /// The bus at `index`, to inspect its counters or transport.
    pub fn bus(&self, index: usize) -> Option<&Bus<T>> {
        self.lanes.get(index).map(|l| &l.bus.bus)
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

    /// Runs one cycle on every bus. Returns false once the run has ended
    /// (the path completed, a stop or fault reaction finished, torque was
    /// turned off); later calls do nothing.
    pub fn step(&mut self) -> bool {
        if self.finish.is_some() {
            return false;
        }
        let k = self.next;
        self.next += 1;
        for (lane, pacer) in self.lanes.iter_mut().zip(&mut self.pacers) {
            // A bus still busy with an earlier cycle has this deadline
            // skipped by its pacer (an overrun), as on threads.
            if lane.finish.is_none() && pacer.next_index() <= k {
                lane.cycle(pacer.wait());
            }
        }
        if self.fault.is_none() {
            self.fault = self.board.first();
        }
        if self.lanes.iter().all(|l| l.finish.is_some()) {
            self.finish = Some(overall(self.lanes.iter().filter_map(|l| l.finish)));
        }
        self.finish.is_none()
    }

    /// The report so far.
    pub fn report(&self) -> Report {
        let ending = Ending {
            rate_hz: self.rate_hz,
            units: self.units,
            finish: self.finish.unwrap_or(Finish::Completed),
            fault: self.fault.clone(),
            warnings: Vec::new(),
            live: self.counters.report(),
        };
        assemble(self.lanes.iter().map(|l| l.bus.outcome()).collect(), ending)
    }

    /// Steps to the end of the run, publishes
    /// [`Telemetry::Finished`], and returns the report. A run waiting for
    /// [`Command::Play`](crate::Command::Play) ends as
    /// [`Finish::Abandoned`] once every other command sender is gone.
    pub fn run(mut self) -> Report {
        self.command_tx = None;
        while self.step() {}
        if let Some(tx) = &self.telemetry_tx {
            let _ = tx.try_send(Telemetry::Finished(
                self.finish.unwrap_or(Finish::Completed),
            ));
        }
        self.report()
    }
}
