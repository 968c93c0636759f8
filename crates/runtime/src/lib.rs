//! servobus-runtime: robot and motion configuration, the real-time
//! scheduler, tracking and safety for robots built from Feetech servos.
//!
//! - [`config`] loads robot and motion files, validates them completely
//!   before anything moves, and maps joint angles to servo ticks.
#![warn(missing_docs)]

pub mod config;

pub mod pacer;
pub mod rt;
pub mod stats;
