//! The facade's tests: a robot opened, connected and played on the built-in
//! simulator and on a pty, and the calibration check of `connect`; the
//! calibration procedure, teaching and the simulator's body (mounting,
//! hand, truth) in virtual time, and live runs on such a body (a leader
//! moved by the hand, a joint against an end stop, the truth compared).

mod base_drive;
mod bench;
mod calib_play;
mod calibrate_arm;
mod calibrate_body;
mod calibrate_lerobot;
mod common;
mod doctor;
mod grasp_hold;
mod live_compare;
mod live_follow;
mod live_stall;
mod play;
mod port;
mod scan;
mod sim_body;
mod teach;
