//! The runtime integration tests, one binary: each module was a test
//! file of its own (linking one binary instead of many).

#[path = "../common/mod.rs"]
mod common;

mod link_silence;
mod live_inputs;
mod live_switch;
mod live_targets;
mod no_alloc;
mod read_time;
mod run_arm;
mod run_faults;
mod run_joint_faults;
mod run_lead;
mod run_limits;
mod run_link;
mod run_robots;
mod run_same_cycle;
mod run_threads;
mod run_wheels;
mod sim_budget;
