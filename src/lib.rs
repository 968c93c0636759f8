//! The `servobus` package: the command line, and the robots and motions
//! built into it ([`builtin`]). The glue between a robot file
//! and the built-in simulator lives in [`servobus_runtime::sim`].
#![warn(missing_docs)]

pub mod builtin;
