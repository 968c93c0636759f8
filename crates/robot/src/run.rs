//! Playing a path on a connection: a run in progress, its telemetry and
//! commands, and its report.

use std::time::Duration;

use crossbeam_channel::Receiver;
use servobus_config::Motion;
use servobus_runtime::grasp::GraspAt;
use servobus_runtime::{
    spawn, Command, CommandSender, Report, RunOptions, Runner, TargetSender, Telemetry, VirtualRun,
    Work,
};
use servobus_trajectory::Trajectory;

use crate::connect::{Connection, RunBuses};
use crate::Error;

/// What to play: a planned path, or a motion (planned when played, at its
/// own rate and in its own units unless the options give them).
#[derive(Debug, Clone)]
pub enum Play {
    /// A planned path.
    Trajectory(Trajectory),
    /// A motion of the robot.
    Motion(Motion),
}

impl From<Trajectory> for Play {
    fn from(t: Trajectory) -> Self {
        Play::Trajectory(t)
    }
}

impl From<Motion> for Play {
    fn from(m: Motion) -> Self {
        Play::Motion(m)
    }
}

impl From<&Motion> for Play {
    fn from(m: &Motion) -> Self {
        Play::Motion(m.clone())
    }
}

/// The grasps `motion`'s keyframes make and end (`grasp:`), at their
/// times on `trajectory` (planned from it): each from the start of the
/// move to its keyframe, in every repetition. Give them to a played run
/// as [`RunOptions::grasps`]; [`Connection::play`] of a motion does.
pub fn motion_grasps(motion: &Motion, trajectory: &Trajectory) -> Vec<GraspAt> {
    let mut out = Vec::new();
    for seg in trajectory.segments() {
        let Some(k) = motion.keyframes.get(seg.keyframe) else {
            continue;
        };
        out.extend(k.grasps.iter().map(|g| GraspAt {
            at_s: seg.start,
            joint: g.joint,
            effort: g.effort.map(|e| e / 100.0),
        }));
    }
    out
}

impl Connection {
    /// Plays `what` on the buses with `options` (see
    /// [`Connection::options`] for the robot's defaults): on the simulator
    /// in virtual time on a thread of its own, otherwise one thread per bus
    /// on the wall clock. The run has started when this returns; the
    /// connection's buses are the run's until it ends.
    ///
    /// # Errors
    /// [`Error::Config`] when a motion's path cannot be planned;
    /// [`Error::Run`] when the run cannot start (a servo does not answer, a
    /// rate that does not fit a bus).
    pub fn play(self, what: impl Into<Play>, mut options: RunOptions) -> Result<Run, Error> {
        let trajectory = match what.into() {
            Play::Trajectory(t) => t,
            Play::Motion(motion) => {
                options.units = options.units.or(Some(motion.units));
                options.rate_hz = options.rate_hz.or(Some(motion.rate_hz(&self.robot)));
                let trajectory = servobus_config::plan_motion(&motion, &self.robot)?;
                if options.grasps.is_empty() {
                    options.grasps = motion_grasps(&motion, &trajectory);
                }
                trajectory
            }
        };
        self.start(Work::Path(trajectory), options)
    }

    /// Starts a live run with `options`: no path, the joints follow the
    /// targets sent through [`Run::targets`] (a jerk-limited step toward
    /// the newest every cycle), and stop and hold when none comes for
    /// `options.target_timeout`. On the simulator in virtual time on a
    /// thread of its own, otherwise one thread per bus on the wall clock.
    ///
    /// # Errors
    /// [`Error::Run`] when the run cannot start (a servo does not answer, a
    /// rate that does not fit a bus).
    pub fn live(self, options: RunOptions) -> Result<Run, Error> {
        self.start(Work::Live, options)
    }

    /// Starts `work`: on the simulator in virtual time on a thread of its
    /// own, otherwise one thread per bus on the wall clock.
    fn start(self, work: Work, options: RunOptions) -> Result<Run, Error> {
        let (robot, buses) = self.into_buses();
        let runner = match buses {
            RunBuses::Serial(b) => spawn(&robot, work, b, options)?,
            RunBuses::Virtual(b) => VirtualRun::of(&robot, work, b, options)?.spawn()?,
            RunBuses::Wall(b) => spawn(&robot, work, b, options)?,
        };
        Ok(Run { runner })
    }
}

/// A run in progress: its telemetry, commands to it, and its report at the
/// end ([`Run::join`]).
#[derive(Debug)]
pub struct Run {
    runner: Runner,
}

impl Run {
    /// The run's telemetry: samples while it runs, then how it finished.
    /// The channel disconnects once the run has ended and every message has
    /// been read.
    pub fn telemetry(&self) -> Receiver<Telemetry> {
        self.runner.telemetry()
    }

    /// A sender of commands to the run, for another thread (a Ctrl-C
    /// handler, a network callback); [`Run::send`] from this one.
    pub fn commands(&self) -> CommandSender {
        self.runner.commands()
    }

    /// Where a live run ([`Connection::live`]) takes its targets.
    pub fn targets(&self) -> TargetSender {
        self.runner.targets()
    }

    /// Sends `command` to the run (it takes effect on every bus in the same
    /// cycle).
    ///
    /// # Errors
    /// [`Error::Run`] when the run has already ended.
    pub fn send(&self, command: Command) -> Result<(), Error> {
        Ok(self.runner.send(command)?)
    }

    /// Stops every joint along a jerk-limited path, holds, and ends the run.
    ///
    /// # Errors
    /// As [`Run::send`].
    pub fn stop(&self) -> Result<(), Error> {
        self.send(Command::Stop)
    }

    /// Slows the path down to a standstill along it (the joints hold on the path).
    ///
    /// # Errors
    /// As [`Run::send`].
    pub fn pause(&self) -> Result<(), Error> {
        self.send(Command::Pause)
    }

    /// Resumes a paused path.
    ///
    /// # Errors
    /// As [`Run::send`].
    pub fn resume(&self) -> Result<(), Error> {
        self.send(Command::Resume)
    }

    /// Turns the torque off on every servo and ends the run.
    ///
    /// # Errors
    /// As [`Run::send`].
    pub fn torque_off(&self) -> Result<(), Error> {
        self.send(Command::TorqueOff)
    }

    /// How long the approach to the path's start takes (zero when the
    /// joints were there already): the path begins that long after the
    /// first cycle.
    pub fn approach(&self) -> Duration {
        self.runner.approach()
    }

    /// Whether the run has ended.
    pub fn is_finished(&self) -> bool {
        self.runner.is_finished()
    }

    /// Waits for the end of the run and returns its report.
    ///
    /// # Errors
    /// [`Error::Run`] when a bus thread failed.
    pub fn join(self) -> Result<Report, Error> {
        Ok(self.runner.join()?)
    }
}
