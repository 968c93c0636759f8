//! A robot plays on a port (a simulated bus on a pseudo-terminal) as on the
//! built-in simulator, and `connect` refuses servos that do not match its
//! calibration before anything is read through it or moves.

use crate::common::{self, repo, Pty};
use servobus_robot::sim::Mounting;
use servobus_robot::{Error, Finish, Refusal, Robot, Target};

#[test]
fn arm_wave_plays_to_the_end_on_a_pty() {
    let robot = Robot::open("so101").expect("opens");
    let pty = Pty::serve(robot.config(), None);
    let motion = robot.motion("arm-wave").expect("the motion");
    let connection = robot
        .connect(Target::Ports(vec![pty.path.clone()]))
        .expect("connects on the pty");
    assert!(!connection.is_simulated());
    let report = common::play_to_end(connection, &motion);
    assert_eq!(report.finish, Finish::Completed);
    assert_eq!(report.joints.len(), 6);
    assert!(report.cycles > 100, "{} cycles", report.cycles);
}

#[test]
fn a_run_on_a_pty_stops_on_command() {
    let robot = Robot::open("so101").expect("opens");
    let pty = Pty::serve(robot.config(), None);
    let connection = robot
        .connect(Target::Ports(vec![pty.path.clone()]))
        .expect("connects on the pty");
    let report = common::stopped_after_some_cycles(&robot, connection);
    assert_eq!(report.finish, Finish::Stopped);
}

/// The SO-101 with the calibration taken on the simulator mounted as
/// `configs/sim/so101-mounting.yaml`.
fn calibrated_arm() -> Robot {
    Robot::options()
        .calibration(repo("testdata/calibration/so101-seam.calibration.yaml"))
        .open(repo("configs/robots/so101.yaml"))
        .expect("the calibrated arm opens")
}

#[test]
fn the_calibration_of_the_mounted_arm_is_accepted_on_it() {
    let robot = calibrated_arm();
    let mounting = Mounting::load(&repo("configs/sim/so101-mounting.yaml"), robot.config())
        .expect("the mounting loads");
    let pty = Pty::serve(robot.config(), Some(mounting));
    let connection = robot.connect(Target::Ports(vec![pty.path.clone()]));
    assert!(connection.is_ok(), "{:?}", connection.err());
}

#[test]
fn another_arm_s_servos_are_refused_by_connect() {
    // Bare shafts, every homing offset 0: not the arm that was calibrated.
    let robot = calibrated_arm();
    let pty = Pty::serve(robot.config(), None);
    match robot.connect(Target::Ports(vec![pty.path.clone()])) {
        Err(Error::Refused { bus, port, refusal }) => {
            assert_eq!((bus.as_str(), port), ("arm", pty.path.clone()));
            // Its joints are far from where the calibrated arm's can be.
            let Refusal::Position { deg, range, .. } = *refusal else {
                panic!("expected a joint outside its calibrated range: {refusal}");
            };
            assert!(deg < range.0 || deg > range.1, "{deg} outside {range:?}");
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
}

#[test]
fn a_port_that_does_not_exist_is_an_open_error() {
    let robot = Robot::open("so101").expect("opens");
    let err = robot
        .connect(Target::Ports(vec!["/dev/servobus-no-such-port".into()]))
        .expect_err("no such port");
    assert!(matches!(err, Error::Open(_)), "{err:?}");
}
