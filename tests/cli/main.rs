//! The cli integration tests, one binary: each module was a test
//! file of its own (linking one binary instead of many).

#[path = "../common/mod.rs"]
mod common;

/// At least three tests at a time, unless `--test-threads` or
/// `RUST_TEST_THREADS` says how many.
///
/// These tests mostly wait: on `servobus` processes that play in real time,
/// on pseudo-terminals, on a simulator's hand. At libtest's default of one
/// test per core, a two-core machine sits about 80 % idle through them
/// (18 s of CPU in a 66 s run); three at a time take 39 s. Four take 30 s,
/// but with the machine otherwise saturated (two busy loops) a real-time
/// run against a pty simulator was then now and then starved into a fault;
/// at three it was not. The tests that load the machine most take turns
/// among themselves (`play_realtime`'s lock), and every wall-clock bound is
/// set for a loaded machine.
///
/// libtest reads `RUST_TEST_THREADS` when it starts running tests, so the
/// variable is set before `main`, from the ELF initialisers (Linux only;
/// elsewhere the default holds).
#[cfg(target_os = "linux")]
#[used]
#[link_section = ".init_array"]
static AT_LEAST_THREE_AT_A_TIME: extern "C" fn() = at_least_three_at_a_time;

#[cfg(target_os = "linux")]
extern "C" fn at_least_three_at_a_time() {
    if std::env::var_os("RUST_TEST_THREADS").is_none() {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        // Before `main`: no other thread exists yet to read the environment.
        std::env::set_var("RUST_TEST_THREADS", cores.max(3).to_string());
    }
}

mod bad_inputs;
mod bench_cli;
mod budget_cli;
mod budget_link;
mod bus_guidance;
mod bus_tools;
mod calibrate_cli;
mod calibrate_flow;
mod calibrate_screen;
mod calibration_offsets;
mod circles;
mod cli_errors;
mod decode_cli;
mod docs;
mod doctor_cli;
mod doctor_servo_settings;
mod exit_codes;
mod facts;
mod first_arm;
mod follow_cli;
mod human_output;
mod install;
mod interpolation_cli;
mod json_output;
mod kinematics_cli;
mod layers;
mod lengths;
mod missing_pty;
mod monitor;
mod monitor_tmux;
mod no_terminal;
mod number_forms;
mod outputs;
mod plan_cli;
mod play_cli;
mod play_measured_rate;
mod play_realtime;
mod play_recording;
mod plot_views;
mod rate_limit_cli;
mod replay_log;
mod rt_fallback;
mod rust_code;
mod scan_cli;
mod sim_body_cli;
mod stream_cli;
mod sweep;
mod teach_cli;
