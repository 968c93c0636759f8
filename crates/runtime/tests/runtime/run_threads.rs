//! The threaded runner (`spawn`): one thread per bus, commands and
//! telemetry over channels. Run here on the simulator's manual clock, so
//! the threads move through virtual time and nothing depends on the wall
//! clock.

use crate::common;

use servobus_runtime::{spawn, Command, Finish, RunOptions, Runner, Telemetry};

/// arm-wave on the threaded runner, waiting for Play so that nothing ends
/// before a test's commands are in.
fn arm_wave_waiting_for_play() -> Runner {
    let (path, robot) = common::motion("arm-wave.yaml");
    let (buses, _) = common::sim_buses(&robot);
    let options = RunOptions {
        autoplay: false,
        ..common::quiet()
    };
    spawn(&robot, path, buses, options).expect("starts")
}

#[test]
fn the_threaded_runner_plays_the_two_bus_hexapod_and_reports() {
    let (m, robot) = servobus_runtime::config::load_motion(
        &common::config("motions/hexapod-tripod.yaml"),
        Some(&common::config("robots/hexapod-2bus.yaml")),
    )
    .expect("loads");
    let path = servobus_runtime::config::plan_motion(&m, &robot).expect("plans");
    let (buses, _) = common::sim_buses(&robot);
    let options = RunOptions {
        telemetry_capacity: 64,
        ..RunOptions::default()
    };
    let runner = spawn(&robot, path, buses, options).expect("starts");
    let telemetry = runner.telemetry();
    let mut finished = None;
    let mut samples = 0u64;
    for m in telemetry.iter() {
        match m {
            Telemetry::Cycle(_) => samples += 1,
            Telemetry::Finished(f) => finished = Some(f),
            _ => {}
        }
    }
    let report = runner.join().expect("joins");
    println!("{}", serde_json::to_string(&report).unwrap_or_default());
    assert_eq!(report.finish, Finish::Completed);
    assert_eq!(finished, Some(Finish::Completed));
    assert!(samples > 0);
    assert_eq!(report.buses.len(), 2);
    assert_eq!(report.joints.len(), 18);
    assert!(report.worst_rms_error() < 0.5);
}

#[test]
fn a_stop_command_reaches_the_threaded_runner() {
    let runner = arm_wave_waiting_for_play();
    // The bus thread runs at CPU speed on its manual clock. The Stop goes
    // first, stamped to a cycle: Play can only arrive after it, so the Stop
    // is pending by the time the path starts and takes effect at its cycle
    // (or at once, should Play come later than that) however the threads
    // are scheduled.
    runner.send_at(300, Command::Stop).expect("running");
    runner.send(Command::Play).expect("running");
    let report = runner.join().expect("joins");
    assert_eq!(report.finish, Finish::Stopped, "{:?}", report.fault);
    assert!(report.fault.is_none());
}

#[test]
fn a_threaded_run_waiting_for_play_is_abandoned_when_no_sender_is_left() {
    let runner = arm_wave_waiting_for_play();
    // join drops the last sender: the run can never start, and ends.
    let report = runner.join().expect("joins");
    assert_eq!(report.finish, Finish::Abandoned);
}
