//! The `servobus` package: the command line, and the glue between a robot
//! file and the built-in simulator that the command line, the examples and
//! the end-to-end tests share.
#![warn(missing_docs)]

pub mod doctor;
pub mod monitor;
pub mod simrobot;
