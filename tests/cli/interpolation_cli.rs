//! Timed keyframes from the command line: the default shape-preserving path
//! stays within its keyframes where the spline (`interpolation: spline`)
//! swings past a joint limit and is refused, and `plan --json` says which
//! interpolation was used.

use crate::common;

use std::path::PathBuf;

use common::{arg, num, one_joint_motion, says, servobus_fails, servobus_json};

/// `motion` as `name`, with the one-joint robot beside it.
fn temp(name: &str, motion: &str) -> PathBuf {
    one_joint_motion("interpolation_cli", name, motion)
}

/// Up to 97 deg, a short step back, then a long way down: a spline through
/// these times swings past 100 deg.
const KEYFRAMES: &str = "keyframes:
  - {at: 0, pose: {a: 0}}
  - {at: 2.5, pose: {a: 97}}
  - {at: 3.5, pose: {a: 80}}
  - {at: 6, pose: {a: -10}}
";

#[test]
fn shape_preserving_by_default_spline_by_name() {
    let m = temp("m.yaml", &format!("robot: robot.yaml\n{KEYFRAMES}"));
    let v = servobus_json(&["plan", arg(&m), "--json"]);
    assert_eq!(v["interpolation"], "shape_preserving", "{v}");
    assert!((num(&v, "duration_s") - 6.0).abs() < 1e-9, "{v}");
    let j = &v["joints"][0];
    assert!(num(j, "max_position") <= 97.0 + 1e-9, "{j}");
    assert!(num(j, "min_position") >= -10.0 - 1e-9, "{j}");
    assert!(num(j, "peak_velocity") <= 90.0 + 1e-9, "{j}");
    assert!(num(j, "peak_acceleration") <= 180.0 + 1e-9, "{j}");

    let s = temp(
        "s.yaml",
        &format!("robot: robot.yaml\ninterpolation: spline\n{KEYFRAMES}"),
    );
    let err = servobus_fails(&["plan", arg(&s)]);
    says(&err, &["peak position", "above the limit 100"]);

    let u = temp(
        "u.yaml",
        "robot: robot.yaml\nkeyframes:\n  - pose: {a: 0}\n  - pose: {a: 50}\n",
    );
    let v = servobus_json(&["plan", arg(&u), "--json"]);
    assert_eq!(v["interpolation"], "untimed", "{v}");
}
