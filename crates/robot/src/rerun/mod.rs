//! A run, a plan or the simulator's truth recorded for the Rerun viewer
//! (cargo feature `rerun`): a `.rrd` file ([`Sink::File`], opened with
//! `rerun FILE.rrd`) or a viewer that is running ([`Sink::Viewer`], by
//! default [`DEFAULT_VIEWER`], where `rerun` listens).
//!
//! A [`Recorder`] is made for a robot, takes a run's [`Telemetry`]
//! ([`Recorder::telemetry`]), poses ([`Recorder::pose`]), a planned path
//! ([`Recorder::plan`]) and events ([`Recorder::event`]), and is
//! [finished](Recorder::finish) once the run has ended. One timeline,
//! `time`: seconds since the start of the run (of the path, for a plan).
//! Lengths are in metres (the URDF's unit, so that its meshes are drawn at
//! their size); angles in the series are in the units the recorder is
//! made with.
//!
//! | entity | what | when |
//! | --- | --- | --- |
//! | `robot` | the robot's base in the world: a legged body's pose from the feet it stands on; an arm's base stays at the origin | per sample (legged) |
//! | `robot/<joint>/<child joint>/...` | one entity per joint, nested as its chain: `Transform3D` from its parent's frame, its origin then the turn about its axis by the measured angle | per sample |
//! | `robot/.../<link>/visual_<k>` | a URDF link's visuals on the joint that carries it: `Asset3D` of its mesh file (scaled as the URDF says), boxes, cylinders, spheres | static |
//! | `robot/.../shape`, `robot/body` | without a URDF: a cylinder along each joint's axis, bones to what it carries, the body's outline | static |
//! | `ghost/...` | the same tree posed by the commanded angles, drawn as translucent bones (none in a plan) | per sample |
//! | `joints/<joint>/commanded`, `measured`, `error` | the goal sent, the reading, the tracking error (`Scalars`) | per sample |
//! | `joints/<joint>/temperature`, `current_ma` | where the run reads them: a grasp's watch | its events |
//! | `joints/<joint>/margin` | a plan: the distance to the nearer joint limit | per sample |
//! | `paths/<frame>` | the tool's, or each foot's, position in the world (`Points3D`); its whole path in `paths/<frame>/trace` | per sample; at the end |
//! | `robot/workspace` | a plan: where the tool or the feet get to over random poses within the limits | static |
//! | `events` | faults, stalls, grasps, refusals, the end of the run (`TextLog`) | at their time |
//!
//! The run's cycle telemetry carries the positions the runtime reads;
//! servo load and temperature are not read every cycle, so their series
//! hold what a run does read (a grasp's temperature and current).
//!
//! The viewer lays a recording out as the robot in 3D beside a plot of
//! each joint's series and the events (a file's default layout; a viewer
//! that is running takes it at once).
//!
//! A sample is logged at most every [`MIN_PERIOD_S`] per bus. A file is
//! written beside its path and takes its place when the recording is
//! finished, whole: a recorder dropped unfinished leaves the path as it
//! was.

mod motion;
mod output;
mod plan;
mod scene;
mod tree;
mod world;

use std::path::PathBuf;

use servobus_config::{Robot, Units};
use servobus_runtime::Telemetry;

use output::Output;

/// The address of a Rerun viewer started with `rerun` on this machine.
pub const DEFAULT_VIEWER: &str = "rerun+http://127.0.0.1:9876/proxy";

/// The shortest time between two logged samples of one bus, s: 100 a
/// second, beyond what a viewer shows and at most half a 200 Hz run.
pub const MIN_PERIOD_S: f64 = 0.0095;

/// The timeline every recording uses: seconds of the run.
pub const TIMELINE: &str = "time";

/// Where a recording goes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Sink {
    /// A `.rrd` file.
    File(PathBuf),
    /// A running viewer at this address (`rerun+http://HOST:PORT/proxy`).
    Viewer(String),
}

/// How an event is shown in the viewer's log.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// Something that happened as it should (a grasp, the end of a run).
    Info,
    /// Something to look at (a stall, a rejected command).
    Warning,
    /// A fault, or a refusal.
    Error,
}

impl Level {
    fn word(self) -> &'static str {
        match self {
            Level::Info => "INFO",
            Level::Warning => "WARN",
            Level::Error => "ERROR",
        }
    }
}

/// Why a recording could not be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RerunError {
    /// The file cannot be written (a directory, a missing directory, a
    /// read-only file).
    #[error(transparent)]
    Output(#[from] crate::files::OutputError),
    /// A viewer's address that is not one.
    #[error("`{address}` is no Rerun viewer's address: {reason} (e.g. {DEFAULT_VIEWER})")]
    Address {
        /// The address given.
        address: String,
        /// What is wrong with it.
        reason: String,
    },
    /// Nothing listens at a viewer's address.
    #[error("no Rerun viewer listens at {address} ({reason}); start one with `rerun`")]
    NoViewer {
        /// The address given.
        address: String,
        /// The connection's error.
        reason: String,
    },
    /// The recording could not be started.
    #[error("cannot record to {what}: {reason}")]
    Start {
        /// The file or address.
        what: String,
        /// Rerun's reason.
        reason: String,
    },
    /// The recording could not be finished (written or sent whole).
    #[error("the recording to {what} could not be finished: {reason}")]
    Finish {
        /// The file or viewer.
        what: String,
        /// The reason.
        reason: String,
    },
}

/// Records a robot's runs, plans or truth; see the [module](self).
pub struct Recorder {
    output: Output,
    /// The units of the angles given.
    units: Units,
    /// Per joint (robot order), its name and series.
    joints: Vec<motion::Series>,
    /// The robot's tree and paths; `None` without geometry.
    space: Option<motion::Space>,
    /// The last state given, per joint, in `units`.
    commanded: Vec<Option<f64>>,
    measured: Vec<Option<f64>>,
    /// Per bus, when a sample was last logged, s.
    last: Vec<f64>,
    /// The latest time logged, s.
    time_s: f64,
    /// The first logging failure, said when finishing.
    failed: Option<String>,
}

impl std::fmt::Debug for Recorder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recorder")
            .field("units", &self.units)
            .field("joints", &self.joints.len())
            .field("time_s", &self.time_s)
            .finish_non_exhaustive()
    }
}

impl Recorder {
    /// Starts recording `robot` to `sink` ([`Sink::check`] first), angles
    /// given in `units`: its tree with the URDF's visuals (or shapes from
    /// its kinematics) and the ghost's bones are logged at once.
    ///
    /// # Errors
    /// Those of [`Sink::check`]; [`RerunError::Start`].
    pub fn create(robot: &Robot, units: Units, sink: &Sink) -> Result<Recorder, RerunError> {
        let joints = motion::Series::of(robot);
        let names: Vec<&str> = joints.iter().map(|j| j.name.as_str()).collect();
        let output = Output::open(sink, &names)?;
        let space = robot.geometry().map(motion::Space::new);
        let mut recorder = Recorder {
            output,
            units,
            commanded: vec![None; joints.len()],
            measured: vec![None; joints.len()],
            joints,
            space,
            last: vec![f64::NEG_INFINITY; robot.buses.len().max(1)],
            time_s: 0.0,
            failed: None,
        };
        if let Some(space) = &recorder.space {
            let logged = scene::log(
                &recorder.output.stream,
                &space.tree,
                robot.urdf.as_ref(),
                &space.paths,
            );
            recorder.note(logged);
        }
        Ok(recorder)
    }

    /// Takes a message of a run's telemetry in: a cycle's sample poses
    /// the robot (measured) and the ghost (commanded) and adds to the
    /// series; faults, stalls, grasps, rejected commands, live following's
    /// pauses and the end of the run are events.
    pub fn telemetry(&mut self, message: &Telemetry) {
        match message {
            Telemetry::Cycle(sample) => self.cycle(sample),
            other => self.telemetry_event(other),
        }
    }

    /// Records an event at `time_s` (`None`: the latest time logged), e.g.
    /// a refusal before anything moved.
    pub fn event(&mut self, time_s: Option<f64>, level: Level, text: &str) {
        let t = time_s.unwrap_or(self.time_s);
        self.set_time(t);
        let log = ::rerun::TextLog::new(text).with_level(level.word());
        let logged = self.output.stream.log("events", &log);
        self.note(logged);
    }

    /// Records the state at `time_s`: the commanded angles (the ghost's)
    /// and the measured ones (the robot's; where `None`, the commanded),
    /// per joint in the robot's order, in the recorder's units (`None`
    /// for a joint not known); the simulator's truth is measured.
    pub fn pose(&mut self, time_s: f64, commanded: &[Option<f64>], measured: &[Option<f64>]) {
        for (slot, v) in self.commanded.iter_mut().zip(commanded) {
            if v.is_some() {
                *slot = *v;
            }
        }
        for (slot, v) in self.measured.iter_mut().zip(measured) {
            if v.is_some() {
                *slot = *v;
            }
        }
        self.set_time(time_s);
        let all: Vec<usize> = (0..self.joints.len()).collect();
        self.log_state(&all, commanded.iter().any(Option::is_some), true);
    }

    /// Ends the recording; see [`Sink`]. A logging failure on the way is
    /// said here.
    ///
    /// # Errors
    /// [`RerunError::Finish`].
    pub fn finish(mut self) -> Result<(), RerunError> {
        self.log_traces();
        let failed = self.failed.take().map(|reason| RerunError::Finish {
            what: self.output.what(),
            reason,
        });
        self.output.finish()?;
        failed.map_or(Ok(()), Err)
    }

    /// Sets the time of what is logged next.
    fn set_time(&mut self, time_s: f64) {
        self.time_s = time_s;
        self.output.stream.set_duration_secs(TIMELINE, time_s);
    }

    /// Keeps the first logging failure.
    fn note(&mut self, result: ::rerun::RecordingStreamResult<()>) {
        if let (Err(e), None) = (result, &self.failed) {
            self.failed = Some(e.to_string());
        }
    }
}
