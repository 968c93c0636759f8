//! Timed keyframes from the command line: the default shape-preserving path
//! stays within its keyframes where the spline (`interpolation: spline`)
//! swings past a joint limit and is refused, and `plan --json` says which
//! interpolation was used.

mod common;

use std::path::PathBuf;

use common::{num, servobus, servobus_json};

fn temp(name: &str, text: &str) -> PathBuf {
    common::temp_file("interpolation_cli", name, text)
}

const ROBOT: &str = "\
name: one
rate: 100
buses:
  - name: bus
    joints:
      - {name: a, id: 1, model: sts3215, min: -100, max: 100, max_velocity: 90, max_acceleration: 180}
";

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
    temp("robot.yaml", ROBOT);
    let m = temp("m.yaml", &format!("robot: robot.yaml\n{KEYFRAMES}"));
    let v = servobus_json(&["plan", m.to_str().expect("utf-8"), "--json"]);
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
    let out = servobus(&["plan", s.to_str().expect("utf-8")]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("peak position") && err.contains("above the limit 100"),
        "{err}"
    );

    let u = temp(
        "u.yaml",
        "robot: robot.yaml\nkeyframes:\n  - pose: {a: 0}\n  - pose: {a: 50}\n",
    );
    let v = servobus_json(&["plan", u.to_str().expect("utf-8"), "--json"]);
    assert_eq!(v["interpolation"], "untimed", "{v}");
}
