//! The `servobus` package: the command line, the robots and motions built
//! into it ([`builtin`]), the text of `servobus doctor`'s findings (the
//! checks are [`servobus_robot::doctor`]'s) and the live view of
//! `servobus monitor`, kept in the library so that they are tested on the
//! simulator in virtual time. The glue between a robot file
//! and the built-in simulator lives in [`servobus_robot::sim`].
#![warn(missing_docs)]

/// The shipped robots, motions and simulator examples, by name (the
/// configuration crate's table).
pub use servobus_config::builtin;
pub mod doctor;
pub mod monitor;
