//! servobus-runtime: robot and motion configuration, the real-time
//! scheduler, tracking and safety for robots built from Feetech servos.
//!
//! - [`config`] loads robot and motion files, validates them completely
//!   before anything moves, and maps joint angles to servo ticks.
//! - [`VirtualRun`] (simulated buses, virtual time, deterministic) and
//!   [`spawn`] (any buses, real clock, one thread per bus in step) play a
//!   trajectory: goals at `t + lead` clamped to the limits, SYNC WRITE,
//!   feedback, tracking, faults with their [`Reaction`], [`Command`]s in and
//!   [`Telemetry`] out over bounded channels, a [`Report`] at the end.
//!   Both run one cycle function per bus; they differ only in the clock and
//!   the pacing, so a test in virtual time runs the code of a real run.
//!
//! Calibration, teaching and the glue that builds a robot file's servos on
//! the simulator are not the scheduler's: they are in `servobus-robot`
//! (`servobus_robot::{calibrate, teach, sim}`).
#![warn(missing_docs)]

/// The robot, motion and calibration files (the `servobus-config` crate).
pub use servobus_config as config;

pub mod grasp;
pub mod pacer;
pub mod rt;
pub mod stats;

// The scheduler: runs a robot + trajectory on its buses, tracks, reacts to
// faults. `lane` holds the one cycle function; `virtual_run` steps the lanes
// in virtual time, `threads` runs each on its own thread; `run` prepares
// both and assembles the report.
mod busloop;
mod command;
mod error;
mod exchange;
mod fault;
mod lane;
mod live;
mod options;
mod report;
mod run;
mod target;
mod telemetry;
mod threads;
mod timeline;
mod virtual_run;

pub use command::Command;
pub use error::RunError;
pub use exchange::{CommandSender, COMMAND_DELAY_CYCLES};
pub use fault::{Fault, FaultKind, STALL_PUSH};
pub use options::{FaultPolicy, Lead, Reaction, RunOptions, BUS_SILENCE};
pub use report::{BusReport, JointReport, Quantiles, Report, SettingDifference};
pub use run::bus_settings;
pub use target::{
    Chunk, LiveJoint, LiveReport, LiveTarget, TargetError, TargetSender, MAX_CHUNK_POINTS,
};
pub use telemetry::{
    CycleSample, Finish, JointSample, LiveEvent, Rejection, StallEvent, Telemetry, SAMPLE_JOINTS,
};
pub use threads::{spawn, Runner, Work};
pub use virtual_run::VirtualRun;
