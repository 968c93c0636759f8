//! The config integration tests, one binary: each module was a test
//! file of its own (linking one binary instead of many).

#[path = "../common/mod.rs"]
mod common;

mod config_bounded;
mod config_errors;
mod config_files;
mod config_grasp;
mod config_mapping;
mod config_motion;
mod config_pose_arg;
mod config_wheel_servo;
