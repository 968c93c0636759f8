//! The facade's tests: a robot opened, connected and played on the built-in
//! simulator and on a pty, and the calibration check of `connect`.

mod bench;
mod common;
mod doctor;
mod play;
mod port;
mod scan;
