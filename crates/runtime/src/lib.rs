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
//! - [`sim`] builds a robot file's servos on the simulator (the glue the
//!   command line, the examples and the tests share).
#![warn(missing_docs)]

pub mod config;

pub mod pacer;
pub mod rt;
pub mod sim;
pub mod stats;

// The scheduler: runs a robot + trajectory on its buses, tracks, reacts to
// faults. See `run` for the two entry points.
mod busloop;
mod command;
mod error;
mod fault;
mod options;
mod report;
mod run;
mod telemetry;
mod timeline;

pub use command::Command;
pub use error::RunError;
pub use fault::{Fault, FaultKind};
pub use options::{FaultPolicy, Lead, Reaction, RunOptions};
pub use report::{BusReport, JointReport, Quantiles, Report};
pub use run::{bus_settings, spawn, spawn_virtual, Runner, VirtualRun};
pub use telemetry::{CycleSample, Finish, JointSample, Telemetry, SAMPLE_JOINTS};
