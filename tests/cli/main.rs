//! The cli integration tests, one binary: each module was a test
//! file of its own (linking one binary instead of many).

#[path = "../common/mod.rs"]
mod common;

mod bad_inputs;
mod bench_cli;
mod budget_cli;
mod budget_link;
mod bus_guidance;
mod bus_tools;
mod calibrate_cli;
mod calibrate_flow;
mod calibration_offsets;
mod cli_errors;
mod decode_cli;
mod doctor_cli;
mod exit_codes;
mod first_arm;
mod follow_cli;
mod human_output;
mod install;
mod interpolation_cli;
mod kinematics_cli;
mod missing_pty;
mod monitor;
mod monitor_tmux;
mod no_terminal;
mod outputs;
mod plan_cli;
mod play_cli;
mod play_measured_rate;
mod play_realtime;
mod play_recording;
mod rate_limit_cli;
mod rt_fallback;
mod scan_cli;
mod sim_body_cli;
mod stream_cli;
mod teach_cli;
