//! A pose on the command line (`fk --pose`): each joint once, a finite
//! angle within its limits, in the robot file's units.

use crate::common;
use servobus_config::{load_robot, parse_pose, PoseError, RobotOptions};

fn so101() -> servobus_config::Robot {
    load_robot(
        &common::config("robots/so101.yaml"),
        &RobotOptions::default().any_rate(),
    )
    .expect("the shipped arm")
}

#[test]
fn a_pose_within_the_limits_is_every_joint_in_radians() {
    let robot = so101();
    let q = parse_pose(&robot, "{shoulder_pan: 110, elbow_flex: -30}").expect("a pose");
    assert_eq!(q.len(), robot.joint_count());
    let pan = robot.joint_index("shoulder_pan").expect("a joint");
    let elbow = robot.joint_index("elbow_flex").expect("a joint");
    assert!((q[pan] - 110f64.to_radians()).abs() < 1e-12);
    assert!((q[elbow] + 30f64.to_radians()).abs() < 1e-12);
    assert_eq!(
        q.iter().filter(|&&a| a == 0.0).count(),
        robot.joint_count() - 2
    );
}

#[test]
fn an_angle_beyond_the_limits_is_refused_with_them() {
    let robot = so101();
    let e = parse_pose(&robot, "{shoulder_pan: 200}").expect_err("beyond 110");
    assert!(matches!(e, PoseError::OutsideLimits { .. }), "{e:?}");
    assert_eq!(
        e.to_string(),
        "`shoulder_pan`: 200 deg is outside its limits [-110, 110] deg"
    );
    let e = parse_pose(&robot, "{shoulder_pan: -110.5}").expect_err("beyond -110");
    assert!(e.to_string().contains("-110.5 deg is outside"), "{e}");
}

#[test]
fn a_joint_given_twice_is_refused() {
    let robot = so101();
    let e = parse_pose(&robot, "{shoulder_pan: 10, shoulder_pan: 20}").expect_err("twice");
    assert!(matches!(e, PoseError::Syntax(_)), "{e:?}");
    assert!(
        e.to_string().contains("`shoulder_pan` is given twice"),
        "{e}"
    );
}

#[test]
fn names_and_numbers_that_are_no_pose_are_refused() {
    let robot = so101();
    let e = parse_pose(&robot, "{elbow: 10}").expect_err("no such joint");
    assert!(
        e.to_string()
            .starts_with("robot `so101` has no joint `elbow` (joints: shoulder_pan,"),
        "{e}"
    );
    for bad in ["{shoulder_pan: .nan}", "{shoulder_pan: .inf}"] {
        let e = parse_pose(&robot, bad).expect_err("not finite");
        assert!(matches!(e, PoseError::NotFinite { .. }), "{bad}: {e:?}");
    }
    for bad in ["[1, 2]", "{shoulder_pan: high}", "30"] {
        let e = parse_pose(&robot, bad).expect_err("not a map of numbers");
        assert!(matches!(e, PoseError::Syntax(_)), "{bad}: {e:?}");
    }
}
