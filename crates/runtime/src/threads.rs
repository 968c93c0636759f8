//! Running a robot on threads ([`spawn`]): one per bus on the buses' clock,
//! each running the same lane cycle as [`VirtualRun`] behind a [`Pacer`], in
//! step from a shared epoch; or a whole [`VirtualRun`] on a thread of its
//! own ([`VirtualRun::spawn`]).

use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use crossbeam_channel::{Receiver, Sender};
use servobus_driver::{Bus, ManualClock, Transport};
use servobus_trajectory::Trajectory;

use crate::busloop::Outcome;
use crate::command::Command;
use crate::config::{Robot, Units};
use crate::error::RunError;
use crate::exchange::{CommandSender, FaultBoard};
use crate::lane::{overall, Lane};
use crate::options::RunOptions;
use crate::pacer::Pacer;
use crate::report::Report;
use crate::rt::RtOptions;
use crate::run::{assemble, prepare, Ending};
use crate::target::{TargetCounts, TargetSender};
use crate::telemetry::{Finish, Telemetry};
use crate::virtual_run::VirtualRun;

/// A run in progress on its own threads.
///
/// The telemetry channel disconnects once the run has ended and every
/// message has been read.
#[derive(Debug)]
pub struct Runner {
    commands: CommandSender,
    targets: TargetSender,
    telemetry: Receiver<Telemetry>,
    handle: JoinHandle<Result<Report, RunError>>,
    approach: Duration,
}

impl Runner {
    /// A sender of commands.
    pub fn commands(&self) -> CommandSender {
        self.commands.clone()
    }

    /// A sender of live targets: the run follows them (a run playing a path
    /// switches to them at the first).
    pub fn targets(&self) -> TargetSender {
        self.targets.clone()
    }

    /// Sends a command (waits if the command channel is full).
    ///
    /// # Errors
    ///
    /// [`RunError::Ended`] when the run has already ended.
    pub fn send(&self, command: Command) -> Result<(), RunError> {
        self.commands.send(command).map_err(|_| RunError::Ended)
    }

    /// Sends a command to take effect in cycle `cycle` on every bus (see
    /// [`CommandSender::send_at`]).
    ///
    /// # Errors
    ///
    /// [`RunError::Ended`] when the run has already ended.
    pub fn send_at(&self, cycle: u64, command: Command) -> Result<(), RunError> {
        self.commands
            .send_at(cycle, command)
            .map_err(|_| RunError::Ended)
    }

    /// A receiver of telemetry.
    pub fn telemetry(&self) -> Receiver<Telemetry> {
        self.telemetry.clone()
    }

    /// How long the approach to the path's start takes, as the run planned
    /// it from the positions read at start-up (zero when the joints were
    /// there already): the path begins that long after the first cycle.
    pub fn approach(&self) -> Duration {
        self.approach
    }

    /// Whether the run has ended.
    pub fn is_finished(&self) -> bool {
        self.handle.is_finished()
    }

    /// Waits for the end of the run and returns its report. A run still
    /// waiting for [`Command::Play`] ends as [`Finish::Abandoned`] once no
    /// other command sender is left.
    ///
    /// # Errors
    ///
    /// [`RunError::Panicked`] when a thread of the run panicked.
    pub fn join(self) -> Result<Report, RunError> {
        drop(self.commands);
        self.handle.join().map_err(|_| RunError::Panicked {
            what: "the run's thread",
        })?
    }
}

/// What a run does: play a planned path, or follow live targets.
#[derive(Debug, Clone)]
pub enum Work {
    /// Play this path (a run playing a path switches to live targets at
    /// the first).
    Path(Trajectory),
    /// No path: the joints hold where they are and follow the live targets
    /// sent through [`Runner::targets`] (see [`VirtualRun::live`]). The run
    /// ends on [`Command::Stop`] (a jerk-limited stop),
    /// [`Command::TorqueOff`] or a fault.
    Live,
}

impl From<Trajectory> for Work {
    fn from(t: Trajectory) -> Self {
        Work::Path(t)
    }
}

impl<T: Transport<Clock = ManualClock> + Send + 'static> VirtualRun<T> {
    /// A run of `work` in virtual time: [`VirtualRun::new`] of a path, or
    /// [`VirtualRun::live`].
    ///
    /// # Errors
    ///
    /// As [`VirtualRun::new`].
    pub fn of(
        robot: &Robot,
        work: Work,
        buses: Vec<Bus<T>>,
        options: RunOptions,
    ) -> Result<Self, RunError> {
        match work {
            Work::Path(trajectory) => VirtualRun::new(robot, trajectory, buses, options),
            Work::Live => VirtualRun::live(robot, buses, options),
        }
    }

    /// Runs this in virtual time on a thread of its own (the built-in
    /// simulator at full speed, as `servobus play --fast` with a progress
    /// bar reading the telemetry), until it ends.
    ///
    /// # Errors
    ///
    /// [`RunError::Spawn`] when the thread cannot start.
    pub fn spawn(self) -> Result<Runner, RunError> {
        let commands = self.commands();
        let targets = self.targets();
        let telemetry = self.telemetry();
        let approach = self.approach();
        let handle = std::thread::Builder::new()
            .name("servobus-virtual".into())
            .spawn(move || Ok(self.run()))
            .map_err(RunError::Spawn)?;
        Ok(Runner {
            commands,
            targets,
            telemetry,
            handle,
            approach,
        })
    }
}

/// What a bus thread hands back.
type LaneEnd = (Outcome, Finish, Vec<String>);

/// Runs `work` on `buses` (one per robot bus, in order) on the clock
/// they were built with, one thread per bus, in step from a shared epoch:
/// cycle `k` of every bus is due at `start + k * period`. (A run on the
/// built-in simulator's virtual time can also run on one thread at full
/// speed: [`VirtualRun::spawn`].)
///
/// The buses' clocks must share their time base (clones of one
/// [`SystemClock`](servobus_driver::SystemClock)). Tests may give each bus
/// its own [`ManualClock`]: each thread then runs through virtual time as
/// fast as it can, commands still take effect at their stamped cycle, and
/// a fault on one bus reaches the others at their next cycle. Start-up (reading
/// positions, enabling torque, planning the approach) happens before this
/// returns; the first cycle is due 50 ms (at least 5 periods) later. Each
/// thread keeps its own copy of the robot-wide path, and commands take
/// effect in the same cycle on every bus.
///
/// # Errors
///
/// As [`VirtualRun::new`]; [`RunError::Spawn`] when a thread cannot start.
pub fn spawn<T: Transport + Send + 'static>(
    robot: &Robot,
    work: impl Into<Work>,
    buses: Vec<Bus<T>>,
    options: RunOptions,
) -> Result<Runner, RunError> {
    let trajectory = match work.into() {
        Work::Path(t) => Some(t),
        Work::Live => None,
    };
    let p = prepare(robot, trajectory, buses, &options)?;
    let mut threads = Vec::with_capacity(p.lanes.len());
    for lane in p.lanes {
        let rt = RtOptions {
            core: options.rt.core.map(|c| c + lane.bus.index),
            fifo_priority: options.rt.fifo_priority,
        };
        let pacer =
            Pacer::new(lane.bus.bus.clock().clone(), p.start, p.period).with_spin(options.spin);
        let handle = std::thread::Builder::new()
            .name(format!("servobus-{}", lane.bus.name))
            .spawn(move || drive(lane, pacer, rt))
            .map_err(RunError::Spawn)?;
        threads.push(handle);
    }
    let end = RunEnd {
        board: p.board,
        rate_hz: p.rate_hz,
        units: p.units,
        telemetry: p.telemetry_tx,
        counters: p.counters,
    };
    let supervisor = std::thread::Builder::new()
        .name("servobus-run".into())
        .spawn(move || end.supervise(threads))
        .map_err(RunError::Spawn)?;
    Ok(Runner {
        commands: p.commands,
        targets: p.targets,
        telemetry: p.telemetry,
        handle: supervisor,
        approach: p.approach,
    })
}

/// What the supervising thread needs to end a threaded run.
struct RunEnd {
    board: Arc<FaultBoard>,
    rate_hz: f64,
    units: Units,
    telemetry: Option<Sender<Telemetry>>,
    counters: Arc<TargetCounts>,
}

impl RunEnd {
    /// Waits for every bus thread, says why the run ended, and reports.
    fn supervise(self, threads: Vec<JoinHandle<LaneEnd>>) -> Result<Report, RunError> {
        let ends = threads
            .into_iter()
            .map(|t| t.join())
            .collect::<Result<Vec<LaneEnd>, _>>()
            .map_err(|_| RunError::Panicked {
                what: "a bus thread",
            })?;
        let finish = overall(ends.iter().map(|e| e.1));
        if let Some(tx) = &self.telemetry {
            let _ = tx.try_send(Telemetry::Finished(finish));
        }
        let mut outcomes = Vec::with_capacity(ends.len());
        let mut warnings = Vec::new();
        for (o, _, w) in ends {
            outcomes.push(o);
            warnings.extend(w);
        }
        let ending = Ending {
            rate_hz: self.rate_hz,
            units: self.units,
            finish,
            fault: self.board.first(),
            warnings,
            live: self.counters.report(),
        };
        Ok(assemble(outcomes, ending))
    }
}

/// A bus thread: its real-time set-up, then the lane's cycles as the pacer
/// releases them, until the lane's run ends.
fn drive<T: Transport>(mut lane: Lane<T>, mut pacer: Pacer<T::Clock>, rt: RtOptions) -> LaneEnd {
    let warnings = crate::rt::apply(rt).warnings;
    let finish = loop {
        if let Some(f) = lane.cycle(pacer.wait()) {
            break f;
        }
    };
    (lane.bus.outcome(), finish, warnings)
}
