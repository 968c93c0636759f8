//! servobus-robot: the library a program drives a robot with.
//!
//! What the `servobus` command line does with a robot, a Rust program does
//! here, as the Python bindings (`python/`) and the Zenoh node do: open a
//! robot file (a path, a built-in name or a YAML text), connect to its
//! buses — the serial ports of the robot file, ports given by the program,
//! or the built-in simulator — with the calibration checked before anything is
//! read or moved, then plan and play motions with telemetry and commands
//! (stop, pause, resume, torque off) and a report at the end. A robot
//! opens, plays and stops the same way on the simulator and on a port.
//!
//! It carries no command line, terminal interface or plotting: its errors
//! are typed ([`Error`]) and name no command-line flag; a slow adapter is
//! data ([`Connection::slow_adapters`]), not a printed warning.
//!
//! ```no_run
//! use servobus_robot::{Robot, Target};
//!
//! let robot = Robot::open("so101")?; // a built-in name, or a robot file
//! let motion = robot.motion("arm-wave")?;
//! // `Target::Ports(vec!["/dev/ttyACM0".into()])` for real servos (or a
//! // `servobus sim` pty); the built-in simulator in virtual time here.
//! let connection = robot.connect(Target::VirtualSimulator)?;
//! let options = connection.options();
//! let run = connection.play(&motion, options)?;
//! let report = run.join()?;
//! println!("{} cycles, {} timeouts", report.cycles, report.timeouts);
//! # Ok::<(), servobus_robot::Error>(())
//! ```
//!
//! `examples/play_motion.rs` of the servobus repository is this, with a
//! `--port` argument:
//!
//! ```sh
//! cargo run --release --example play_motion -- configs/motions/arm-wave.yaml --port /dev/ttyACM0
//! cargo run --release --example play_motion -- arm-wave   # the built-in simulator
//! ```
//!
//! # The four things most programs do
//!
//! Each is an example of this crate, shown here in full, that runs as
//! written on the built-in simulator, without hardware:
//! `cargo run -p servobus-robot --example NAME`.
//!
//! **Open a robot and play a motion** (`open_and_play`): [`Robot::open`],
//! [`Robot::motion`], [`Robot::connect`], [`Connection::play`], and the
//! [`Report`] of [`Run::join`].
//!
#![doc = concat!("````no_run\n", include_str!("../examples/open_and_play.rs"), "````")]
//!
//! **Stream targets to a live run** (`stream`): [`Connection::live`], a
//! [`LiveTarget`] every 20 ms and then a [`Chunk`] through
//! [`Run::targets`], a stop, and how the run kept to the targets
//! ([`Report::live`]).
//!
#![doc = concat!("````no_run\n", include_str!("../examples/stream.rs"), "````")]
//!
//! **Calibrate an arm** (`calibrate`): the procedure of
//! [`calibrate::calibrate`] on the simulator, a scripted [`sim::Hand`]
//! moving the joints of an arm whose horns were fitted anywhere
//! ([`sim::Mounting::random`]), the calibration written to a file and the
//! robot opened with it ([`LoadOptions::calibration`]).
//!
#![doc = concat!("````no_run\n", include_str!("../examples/calibrate.rs"), "````")]
//!
//! **Check the servos** (`doctor`): [`Robot::doctor`], each
//! [`Finding`](doctor::Finding) with its severity and its fix as data.
//!
#![doc = concat!("````no_run\n", include_str!("../examples/doctor.rs"), "````")]
//!
//! # The modules
//!
//! Live following ([`Connection::live`], targets through
//! [`Run::targets`]) starts the same way as a path; [`stream`] reads the
//! line format every front end streams targets and chunks in (one JSON
//! object a line). [`summary`] says what a planned motion does, as figures
//! (`servobus plan --json`). Beside runs:
//! [`scan`] finds the servos on a port at every baud rate, [`bench`](mod@bench)
//! measures how fast a bus's full cycle runs, [`monitor`] samples what
//! every servo of a bus is doing, and [`doctor`] checks the servos against
//! the robot file and the usual set-up mistakes, each finding with its fix
//! as data:
//!
//! ```no_run
//! use servobus_robot::doctor::{CheckOptions, Severity};
//! use servobus_robot::Robot;
//!
//! let robot = Robot::open("so101")?;
//! // On the robot file's ports, or these; the built-in simulator when no
//! // bus has a port. `fix: true` applies the fixes that are writes.
//! let checkup = robot.doctor(&["/dev/ttyACM0"], &CheckOptions::default())?;
//! for bus in &checkup.buses {
//!     for finding in bus.standing() {
//!         if finding.severity >= Severity::Warning {
//!             println!("{} servo {:?}: {}", finding.severity, finding.id, finding.problem);
//!             if let Some(fix) = finding.advice.command() {
//!                 println!("  fix: {fix:?}"); // e.g. Fix::Write { id, register, value, .. }
//!             }
//!         }
//!     }
//! }
//! # Ok::<(), servobus_robot::Error>(())
//! ```
//!
//! Below the [`Robot`] and its [`Connection`], for programs that drive the
//! steps themselves: [`calibrate`] holds the procedure `servobus calibrate`
//! runs and the check that refuses to move a robot whose calibration does
//! not fit its servos ([`Refusal`]), [`teach`] turns poses or a path taught
//! by hand into a motion file, and [`sim`] builds a robot file's servos on
//! the simulator, with a body (mounting, hand, truth recorder) when asked:
//! the glue the command line, the examples and the tests share.
//!
//! And below a robot, for tools that work on one bus or one file: [`bus`]
//! is a servo bus by itself (transactions by ID, registers, stop signals),
//! [`ports`] says which port each bus is on and opens a bus on it (with
//! reply deadlines that allow for the adapter's latency), [`timing`] the
//! baud budget of a control cycle, [`path`] a planned path's states and
//! how a recording is followed within the limits, and [`files`] the output
//! files written whole or not at all. The command line, the Python
//! bindings and the Zenoh node use this crate and the data crates it
//! re-exports ([`config`], `servobus-protocol`, `servobus-kinematics`) and
//! nothing else of servobus.

pub mod bench;
pub mod bus;
pub mod calibrate;
mod connect;
pub mod doctor;
mod error;
pub mod files;
pub mod monitor;
pub mod odometry;
pub mod path;
pub mod ports;
#[cfg(feature = "rerun")]
pub mod rerun;
mod run;
pub mod scan;
pub mod sim;
pub mod stream;
pub mod summary;
pub mod teach;
pub mod timing;

use std::path::{Path, PathBuf};

pub use connect::{
    live_options, ConnectOptions, Connection, SlowAdapter, Target, APPROACH, SETTLE,
};
pub use error::Error;
pub use run::{motion_grasps, Play, Run};

pub use calibrate::Refusal;
/// The robot, motion and calibration files ([`servobus_config`]).
pub use servobus_config as config;
pub use servobus_config::Motion;
/// Where a run's bus threads run (core, SCHED_FIFO priority).
/// Grasps: a gripper closing on an object and holding it with a bounded
/// effort, watched for heat.
pub use servobus_runtime::grasp;
pub use servobus_runtime::rt::RtOptions;
pub use servobus_runtime::{
    Chunk, Command, CommandSender, CycleSample, Finish, JointSample, Lead, LiveEvent, LiveTarget,
    Rejection, Report, RunError, RunOptions, StallEvent, TargetError, TargetSender, Telemetry,
    VirtualRun, MAX_CHUNK_POINTS,
};
pub use servobus_trajectory::Trajectory;

/// How a robot is loaded; see [`Robot::options`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// The calibration file to apply instead of the one the robot file
    /// names.
    pub calibration: Option<PathBuf>,
    /// Accept a default rate that does not fit every bus (a run then gives
    /// its own rate).
    pub any_rate: bool,
}

impl LoadOptions {
    /// Applies the calibration file `path` instead of the one the robot
    /// file names.
    #[must_use]
    pub fn calibration(mut self, path: impl Into<PathBuf>) -> Self {
        self.calibration = Some(path.into());
        self
    }

    /// Accepts a default rate that does not fit every bus.
    #[must_use]
    pub fn any_rate(mut self) -> Self {
        self.any_rate = true;
        self
    }

    /// These options as the configuration loader takes them.
    fn config_options(&self) -> servobus_config::RobotOptions {
        servobus_config::RobotOptions {
            any_rate: self.any_rate,
            ..Default::default()
        }
        .calibration(self.calibration.as_deref())
    }

    /// Opens the robot `name_or_path`: an existing robot file, or else a
    /// built-in robot's name (`so101`).
    ///
    /// # Errors
    /// [`Error::Config`] naming the file, line, column and field of the
    /// first problem in the robot or calibration file.
    pub fn open(self, name_or_path: impl AsRef<Path>) -> Result<Robot, Error> {
        let path = servobus_config::builtin::robot_path_or_name(name_or_path.as_ref());
        let config = servobus_config::load_robot(&path, &self.config_options())?;
        Ok(Robot {
            config,
            options: self,
            from_text: false,
        })
    }

    /// Loads the motion `name_or_path` (a motion file, or a built-in name)
    /// and opens the robot it names, both validated in full.
    ///
    /// # Errors
    /// As [`LoadOptions::open`], for either file (and a calibration file the
    /// robot names that does not exist: motions are kept within the
    /// calibrated limits).
    pub fn motion(self, name_or_path: impl AsRef<Path>) -> Result<(Robot, Motion), Error> {
        let path = servobus_config::builtin::motion_path_or_name(name_or_path.as_ref());
        let (motion, config) =
            servobus_config::load_motion_calibrated(&path, None, self.calibration.as_deref())?;
        let robot = Robot {
            config,
            options: self,
            from_text: false,
        };
        Ok((robot, motion))
    }

    /// Opens a robot file given as `text` (errors call it `<text>`; a
    /// calibration file it names is relative to the current directory).
    ///
    /// # Errors
    /// As [`LoadOptions::open`].
    pub fn from_yaml(self, text: &str) -> Result<Robot, Error> {
        let source = servobus_config::RobotSource::Text {
            name: Path::new("<text>"),
            text,
        };
        let config = servobus_config::load_robot(source, &self.config_options())?;
        Ok(Robot {
            config,
            options: self,
            from_text: true,
        })
    }
}

impl From<servobus_config::Robot> for Robot {
    /// A robot loaded through [`servobus_config`] (its motions load from
    /// its file, with the calibration it names).
    fn from(config: servobus_config::Robot) -> Self {
        Robot {
            config,
            options: LoadOptions::default(),
            from_text: false,
        }
    }
}

/// A robot: its buses, servos and joint limits (with its calibration
/// applied), ready to [`connect`](Robot::connect).
#[derive(Debug, Clone)]
pub struct Robot {
    config: servobus_config::Robot,
    options: LoadOptions,
    from_text: bool,
}

impl Robot {
    /// The options of loading a robot: `Robot::options().calibration(path).open("so101")`.
    pub fn options() -> LoadOptions {
        LoadOptions::default()
    }

    /// Opens the robot `name_or_path` (a robot file, or a built-in name)
    /// with the calibration it names; see [`LoadOptions::open`].
    ///
    /// # Errors
    /// As [`LoadOptions::open`].
    pub fn open(name_or_path: impl AsRef<Path>) -> Result<Robot, Error> {
        LoadOptions::default().open(name_or_path)
    }

    /// Opens a robot file given as a YAML `text`; see [`LoadOptions::from_yaml`].
    ///
    /// # Errors
    /// As [`LoadOptions::open`].
    pub fn from_yaml(text: &str) -> Result<Robot, Error> {
        LoadOptions::default().from_yaml(text)
    }

    /// Loads the motion `name_or_path` and opens the robot it names; see
    /// [`LoadOptions::motion`].
    ///
    /// # Errors
    /// As [`LoadOptions::motion`].
    pub fn of_motion(name_or_path: impl AsRef<Path>) -> Result<(Robot, Motion), Error> {
        LoadOptions::default().motion(name_or_path)
    }

    /// The robot as its file describes it, calibration applied.
    pub fn config(&self) -> &servobus_config::Robot {
        &self.config
    }

    /// Its name.
    pub fn name(&self) -> &str {
        &self.config.name
    }

    /// Loads the motion `name_or_path` (a motion file, or a built-in name)
    /// for this robot, whatever robot the motion file names, with this
    /// robot's calibration.
    ///
    /// # Errors
    /// [`Error::Config`] for an invalid motion (or a calibration file the
    /// robot names that does not exist: motions are kept within the
    /// calibrated limits); [`Error::NoRobotFile`] for a robot given as text.
    pub fn motion(&self, name_or_path: impl AsRef<Path>) -> Result<Motion, Error> {
        if self.from_text {
            return Err(Error::NoRobotFile {
                robot: self.config.name.clone(),
            });
        }
        let path = servobus_config::builtin::motion_path_or_name(name_or_path.as_ref());
        let (motion, _) = servobus_config::load_motion_calibrated(
            &path,
            Some(&self.config.path),
            self.options.calibration.as_deref(),
        )?;
        Ok(motion)
    }

    /// Loads a motion given as YAML `text` (a message, a form; errors call
    /// it `<motion text>`, with the line and column in it) for this robot,
    /// as [`Robot::motion`] loads a file.
    ///
    /// # Errors
    /// As [`Robot::motion`].
    pub fn motion_from_yaml(&self, text: &str) -> Result<Motion, Error> {
        if self.from_text {
            return Err(Error::NoRobotFile {
                robot: self.config.name.clone(),
            });
        }
        let (motion, _) = servobus_config::load_motion_text(
            Path::new("<motion text>"),
            text,
            Some(&self.config.path),
            self.options.calibration.as_deref(),
        )?;
        Ok(motion)
    }

    /// Plans `motion`'s path for this robot: jerk-limited, within the
    /// joint limits.
    ///
    /// # Errors
    /// [`Error::Config`] when the path cannot be planned.
    pub fn plan(&self, motion: &Motion) -> Result<Trajectory, Error> {
        Ok(servobus_config::plan_motion(motion, &self.config)?)
    }

    /// Connects to the robot's buses at `target`; see [`Connection`].
    ///
    /// # Errors
    /// [`Error::NoPort`], [`Error::TooManyPorts`], [`Error::Open`] when the
    /// buses cannot be opened; [`Error::Refused`] when the servos do not
    /// match the calibration; [`Error::Simulator`] when the robot cannot be
    /// simulated.
    pub fn connect(&self, target: Target) -> Result<Connection, Error> {
        Connection::open(&self.config, target, ConnectOptions::default())
    }

    /// Connects as [`Robot::connect`] does, and does what `options` ask
    /// beside: with [`ConnectOptions::write_servos`], what the robot file
    /// asks of the servos' EEPROM is stored before the calibration is
    /// checked ([`Connection::stored_settings`] says what was).
    ///
    /// # Errors
    /// Those of [`Robot::connect`], and [`Error::Store`] when a servo does
    /// not take a write.
    pub fn connect_with(
        &self,
        target: Target,
        options: ConnectOptions,
    ) -> Result<Connection, Error> {
        Connection::open(&self.config, target, options)
    }

    /// Connects to the robot's built-in simulator (`target` is
    /// [`Target::VirtualSimulator`] or [`Target::Simulator`]) with every
    /// shaft at `pose` instead of at rest: one angle per joint, in the
    /// robot's joint order and the robot file's units. Real servos start
    /// where they are: any other target is [`Error::PoseOnHardware`].
    ///
    /// # Errors
    /// [`Error::PoseOnHardware`]; [`Error::Simulator`] when the robot
    /// cannot be simulated, or `pose` does not fit it.
    pub fn connect_at(&self, target: Target, pose: &[f64]) -> Result<Connection, Error> {
        match target {
            Target::VirtualSimulator | Target::Simulator => {
                Connection::simulated(&self.config, target == Target::Simulator, Some(pose))
            }
            Target::RobotFile | Target::Ports(_) => Err(Error::PoseOnHardware),
        }
    }

    /// Checks every bus of the robot with the doctor ([`doctor::check`]):
    /// on `ports` (the first for the first bus, the robot file's `port:`
    /// past them), or on the built-in simulator when no bus has a port.
    /// The servos are examined as they are, not refused: a calibration
    /// that does not match is a finding.
    ///
    /// # Errors
    /// As [`doctor::check`].
    pub fn doctor<S: AsRef<str>>(
        &self,
        ports: &[S],
        options: &doctor::CheckOptions,
    ) -> Result<doctor::Checkup, Error> {
        doctor::check(&self.config, ports, options)
    }
}
