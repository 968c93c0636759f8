//! A robot opened by name or from text plays on the built-in simulator, in
//! virtual time and on the wall clock, and stops on command.

use crate::common;
use servobus_robot::{Error, Finish, Robot, Target};

#[test]
fn a_built_in_robot_plays_arm_wave_in_virtual_time_to_the_end() {
    let robot = Robot::open("so101").expect("the built-in arm opens by name");
    assert_eq!(robot.name(), "so101");
    let motion = robot.motion("arm-wave").expect("the built-in motion loads");
    let connection = robot.connect(Target::VirtualSimulator).expect("connects");
    assert!(connection.is_simulated());
    assert!(connection.slow_adapters().is_empty());
    let options = connection.options();
    let run = connection.play(&motion, options).expect("the run starts");
    let report = run.join().expect("a report");
    assert_eq!(report.finish, Finish::Completed);
    assert_eq!(report.timeouts, 0);
    assert_eq!(report.joints.len(), 6, "one report per joint of the arm");
    assert!(report.cycles > 100, "{} cycles", report.cycles);
    // At its planned rate, nothing missed, and within the runtime's stated
    // tracking bound of 0.5 deg RMS on the simulator.
    assert_eq!(report.achieved_rate_hz, report.planned_rate_hz);
    assert_eq!((report.overruns, report.missed_replies), (0, 0));
    assert!(
        report.worst_rms_error() < 0.5,
        "{}",
        report.worst_rms_error()
    );
}

#[test]
fn a_robot_given_as_text_opens_and_plays_a_planned_path() {
    let text = std::fs::read_to_string(common::repo("configs/robots/so101.yaml"))
        .expect("the arm's robot file");
    let robot = Robot::from_yaml(&text).expect("the text is a robot file");
    assert_eq!(robot.name(), "so101");
    let by_file = Robot::open(common::repo("configs/robots/so101.yaml")).expect("by path");
    let motion = by_file.motion("arm-wave").expect("the motion");
    let path = robot
        .plan(&motion)
        .expect("plans for the robot given as text");
    let connection = robot.connect(Target::VirtualSimulator).expect("connects");
    let report = common::play_to_end(connection, path);
    assert_eq!(report.finish, Finish::Completed);
    assert_eq!(report.timeouts, 0);
    // Its motions need a robot file to name.
    assert!(matches!(
        robot.motion("arm-wave"),
        Err(Error::NoRobotFile { robot }) if robot == "so101"
    ));
}

#[test]
fn a_bad_text_is_a_located_configuration_error() {
    let err = Robot::from_yaml("name: x\nbuses: 3\n").expect_err("not a robot file");
    let Error::Config(config) = err else {
        panic!("expected a configuration error, got {err:?}");
    };
    assert_eq!(config.file(), std::path::Path::new("<text>"));
    assert!(config.position().is_some(), "{config}");
}

#[test]
fn a_run_on_the_wall_clock_simulator_stops_on_command() {
    let robot = Robot::open("so101").expect("opens");
    let connection = robot.connect(Target::Simulator).expect("connects");
    let report = common::stopped_after_some_cycles(&robot, connection);
    assert_eq!(report.finish, Finish::Stopped);
}

#[test]
fn a_run_held_at_its_start_turns_the_torque_off_on_command() {
    let robot = Robot::open("so101").expect("opens");
    let motion = robot.motion("arm-wave").expect("the motion");
    let connection = robot.connect(Target::VirtualSimulator).expect("connects");
    let options = servobus_robot::RunOptions {
        autoplay: false,
        ..connection.options()
    };
    let run = connection.play(&motion, options).expect("starts");
    run.torque_off().expect("the waiting run takes the command");
    let report = run.join().expect("a report");
    assert_eq!(report.finish, Finish::TorqueOff);
}

#[test]
fn a_new_path_for_another_robot_is_rejected_with_its_joint_counts() {
    use servobus_robot::{Command, Rejection, Telemetry};
    use std::time::Duration;

    let mini = Robot::open("scs-mini").expect("the built-in SCS robot opens");
    let nod = mini.motion("scs-mini-nod").expect("its motion");
    let four_joints = mini.plan(&nod).expect("plans");

    let arm = Robot::open("so101").expect("opens");
    let motion = arm.motion("arm-wave").expect("the motion");
    // On the wall clock: the telemetry is read as fast as it comes, so the
    // rejection is not dropped from a full channel.
    let connection = arm.connect(Target::Simulator).expect("connects");
    let options = connection.options();
    let run = connection.play(&motion, options).expect("starts");
    let telemetry = run.telemetry();
    run.send(Command::replace(four_joints))
        .expect("the run takes the command");
    let rejection = loop {
        match telemetry.recv_timeout(Duration::from_secs(30)) {
            Ok(Telemetry::Rejected(why)) => break why,
            Ok(Telemetry::Finished(finish)) => panic!("ended ({finish:?}) without a rejection"),
            Ok(_) => {}
            Err(e) => panic!("the run sends telemetry: {e}"),
        }
    };
    assert_eq!(
        rejection,
        Rejection::NewPathJoints {
            expected: 6,
            given: 4
        }
    );
    assert_eq!(
        rejection.to_string(),
        "the new path has 4 joints, the robot 6"
    );
    // The run goes on as before, and stops on command.
    run.stop().expect("the run takes the command");
    let report = run.join().expect("a report");
    assert_eq!(report.finish, Finish::Stopped);
}

#[test]
fn a_motion_given_as_text_plays_as_its_file_does() {
    let robot = Robot::open("so101").expect("the built-in arm");
    let text = "robot: so101\nkeyframes:\n  - pose: {shoulder_pan: 0}\n  - {at: 0.5, pose: {shoulder_pan: 10}}\n";
    let motion = robot.motion_from_yaml(text).expect("the text is a motion");
    assert_eq!(motion.keyframes.len(), 2);
    let connection = robot.connect(Target::VirtualSimulator).expect("connects");
    let report = common::play_to_end(connection, &motion);
    assert_eq!(report.finish, Finish::Completed);
    // A bad one is located in the text.
    let err = robot
        .motion_from_yaml("keyframes:\n  - pose: {elbow: 5}\n")
        .expect_err("no such joint");
    let Error::Config(config) = err else {
        panic!("expected a configuration error, got {err:?}");
    };
    assert_eq!(config.file(), std::path::Path::new("<motion text>"));
    assert_eq!(config.position().map(|(line, _)| line), Some(2), "{config}");
    assert!(config.to_string().contains("elbow"), "{config}");
}
