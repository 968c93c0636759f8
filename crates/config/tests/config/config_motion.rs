//! Motion files resolve against their robot: named and partial poses,
//! inherited values, options, relative robot paths and overrides.

use crate::common;

use std::path::PathBuf;

use servobus_config::{load_motion, Interpolation, OnLimit, Units};

fn write(dir: &str, name: &str, text: &str) -> PathBuf {
    common::temp_file(&format!("config_motion/{dir}"), name, text)
}

const ROBOT: &str = "\
name: three
rate: 50
buses:
  - name: bus
    joints:
      - {name: a, id: 1, model: sts3215, min: -90, max: 90, max_velocity: 90, max_acceleration: 400, home: 10}
      - {name: b, id: 2, model: sts3215, min: 5, max: 45, max_velocity: 90, max_acceleration: 400}
      - {name: c, id: 3, model: STS-3215, min: -45, max: 45, max_velocity: 90, max_acceleration: 400, max_jerk: 4000}
";

#[test]
fn partial_poses_keep_previous_values_and_start_from_home() {
    write("partial/robots", "r.yaml", ROBOT);
    let p = write(
        "partial/motions",
        "m.yaml",
        "robot: ../robots/r.yaml\nposes:\n  up: {a: 45, c: 20}\nkeyframes:\n  - pose: {c: 1}\n  - {at: 1, pose: up}\n  - {pose: {a: -5}}\nrepeat: 2\non_limit: stretch\ninterpolation: quintic\n",
    );
    let (m, r) = load_motion(&p, None).expect("valid motion");
    assert_eq!(m.joints, ["a", "b", "c"]);
    // a starts at its home (10); b has no home and 0 is below its min: 5.
    assert_eq!(m.keyframes[0].positions, [10.0, 5.0, 1.0]);
    assert_eq!(m.keyframes[1].positions, [45.0, 5.0, 20.0]);
    assert_eq!(m.keyframes[1].pose.as_deref(), Some("up"));
    assert_eq!(m.keyframes[1].at, Some(1.0));
    assert_eq!(m.keyframes[2].positions, [-5.0, 5.0, 20.0]);
    assert_eq!((m.keyframes[2].line, m.keyframes[2].column), (7, 5));
    assert_eq!(m.repeat, 2);
    assert_eq!(m.on_limit, OnLimit::Stretch);
    assert_eq!(m.interpolation, Interpolation::Quintic);
    assert_eq!(m.rate_hz(&r), 50.0);
    assert!(m.keyframe_location(2).ends_with("m.yaml:7:5"));
    assert_eq!(r.joint("c").and_then(|j| j.max_jerk), Some(4000.0));
}

#[test]
fn robot_override_and_units_conversion() {
    let r = write("override", "robot.yaml", ROBOT);
    let p = write(
        "override",
        "m.yaml",
        "robot: does-not-exist.yaml\nunits: rad\nrate: 25\nkeyframes:\n  - pose: {a: 1.5, b: 0.5}\n",
    );
    let (m, robot) = load_motion(&p, Some(&r)).expect("override used");
    assert_eq!(m.robot_path, r);
    assert_eq!(m.units, Units::Rad);
    assert_eq!(m.rate_hz(&robot), 25.0);
    // c inherits its rest position (0 deg) converted to the motion's units.
    assert_eq!(m.keyframes[0].positions, [1.5, 0.5, 0.0]);
    // Without the override the missing robot is a read error.
    let e = load_motion(&p, None).expect_err("no such robot");
    assert!(e.to_string().contains("does-not-exist.yaml"), "{e}");
}

#[test]
fn a_builtin_robot_name_in_a_motion_file_is_the_builtin_robot() {
    let motion = "robot: so101\nkeyframes:\n  - pose: {shoulder_pan: 10}\n  - {at: 1, pose: {shoulder_pan: -10}}\n";
    let p = write("builtin-name", "m.yaml", motion);
    let (m, r) = load_motion(&p, None).expect("robot: so101 loads");
    assert_eq!(r.name, "so101");
    assert_eq!(m.robot_path, PathBuf::from("<built-in>/robots/so101.yaml"));
    assert_eq!(m.joints.len(), 6);
    // With the `.yaml`, as `--robot` takes it.
    let p = write(
        "builtin-name-yaml",
        "m.yaml",
        &motion.replace("so101", "so101.yaml"),
    );
    let (m, _) = load_motion(&p, None).expect("robot: so101.yaml loads");
    assert_eq!(m.robot_path, PathBuf::from("<built-in>/robots/so101.yaml"));
}

#[test]
fn a_file_beside_the_motion_wins_over_a_builtin_name() {
    // A robot file called `so101` next to the motion: it is the robot.
    let robot = write("builtin-shadowed", "so101", ROBOT);
    let p = write(
        "builtin-shadowed",
        "m.yaml",
        "robot: so101\nkeyframes:\n  - pose: {a: 1}\n",
    );
    let (m, r) = load_motion(&p, None).expect("the file beside it loads");
    assert_eq!(r.name, "three");
    assert_eq!(m.robot_path, robot);
}

#[test]
fn a_robot_that_is_neither_a_file_nor_a_builtin_is_refused_at_its_line() {
    let p = write(
        "builtin-unknown",
        "m.yaml",
        "keyframes:\n  - pose: {a: 1}\nrobot: so102\n",
    );
    let err = load_motion(&p, None)
        .expect_err("no such robot")
        .to_string();
    assert!(err.contains("m.yaml:3:"), "{err}");
    assert!(err.contains("so102") && err.contains("so101"), "{err}");
}
