//! servobus-timing: what every byte, reply and control cycle costs on a
//! Feetech serial bus. Pure integer arithmetic: no I/O, no clock.
#![warn(missing_docs)]

mod link;

pub use link::Link;
