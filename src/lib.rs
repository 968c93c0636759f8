//! The `servobus` package: the command line. The glue between a robot file
//! and the built-in simulator lives in [`servobus_runtime::sim`].
#![warn(missing_docs)]
