//! `servobus plan` on the shipped motions and on small motions whose figures
//! are worked out by hand.

use crate::common;

use std::path::{Path, PathBuf};

use common::{
    arg, num, one_joint_motion, says, servobus_fails, servobus_json, servobus_ok, stdout,
};

/// `motion`, for the one-joint robot, in a folder `dir` of its own: its
/// path. The joint has no jerk limit, so rest-to-rest moves are trapezoids.
fn motion(dir: &str, name: &str, motion: &str) -> PathBuf {
    one_joint_motion(&format!("plan_cli/{dir}"), name, motion)
}

/// `servobus plan MOTION --json`, which must succeed.
fn plan_json(motion: &Path) -> serde_json::Value {
    servobus_json(&["plan", arg(motion), "--json"])
}

/// `servobus plan MOTION`, which must fail: its standard error.
fn plan_error(motion: &Path) -> String {
    servobus_fails(&["plan", arg(motion)])
}

#[test]
fn a_trapezoid_worked_out_by_hand() {
    let m = motion(
        "trapezoid",
        "m.yaml",
        "robot: robot.yaml\nkeyframes:\n  - pose: {a: 0}\n  - pose: {a: 90}\n",
    );
    let v = plan_json(&m);
    // 90 deg at 90 deg/s and 180 deg/s^2: 0.5 s to reach full speed
    // (22.5 deg), 45 deg cruising (0.5 s), 0.5 s to stop: 1.5 s.
    assert!((num(&v, "duration_s") - 1.5).abs() < 1e-9, "{v}");
    let j = &v["joints"][0];
    assert_eq!(j["name"], "a");
    assert!((num(j, "peak_velocity") - 90.0).abs() < 1e-9);
    assert!((num(j, "peak_acceleration") - 180.0).abs() < 1e-9);
    // The acceleration steps: no finite jerk.
    assert!(j["peak_jerk"].is_null(), "{j}");
    assert!(num(j, "min_position").abs() < 1e-9);
    assert!((num(j, "max_position") - 90.0).abs() < 1e-9);
}

#[test]
fn arm_wave_respects_every_limit_and_stays_within_its_keyframes() {
    let v = plan_json(Path::new("configs/motions/arm-wave.yaml"));
    assert!(num(&v, "duration_s") > 1.0);
    let joints = v["joints"].as_array().expect("joints");
    // Per joint: the limits of configs/robots/so101.yaml (velocity,
    // acceleration, jerk) and the range its keyframes in arm-wave.yaml span.
    let expected = [
        ("shoulder_pan", 180.0, 900.0, 9000.0, 0.0, 20.0),
        ("shoulder_lift", 150.0, 700.0, 7000.0, -90.0, -20.0),
        ("elbow_flex", 180.0, 900.0, 9000.0, -30.0, 90.0),
        ("wrist_flex", 240.0, 1200.0, 12000.0, -40.0, 45.0),
        ("wrist_roll", 270.0, 1500.0, 15000.0, -30.0, 30.0),
        ("gripper", 240.0, 1500.0, 15000.0, 10.0, 40.0),
    ];
    assert_eq!(joints.len(), expected.len(), "{v}");
    for (j, (name, vmax, amax, jmax, lo, hi)) in joints.iter().zip(expected) {
        assert_eq!(j["name"], name);
        let tol = 1e-6;
        assert!(num(j, "peak_velocity") <= vmax * (1.0 + tol), "{j}");
        assert!(num(j, "peak_acceleration") <= amax * (1.0 + tol), "{j}");
        assert!(num(j, "peak_jerk") <= jmax * (1.0 + tol), "{j}");
        // Passing through keyframes without stopping must not overshoot them.
        assert!((num(j, "min_position") - lo).abs() < 1e-6, "{j}");
        assert!((num(j, "max_position") - hi).abs() < 1e-6, "{j}");
    }
}

#[test]
fn timed_keyframes_end_exactly_on_time() {
    let v = plan_json(Path::new("configs/motions/arm-pick-place.yaml"));
    // The last keyframe is `at: 10.0`.
    assert!((num(&v, "duration_s") - 10.0).abs() < 1e-9, "{v}");
    let gripper = &v["joints"][5];
    // Monotone interpolation: the gripper never closes past its 5 deg keyframe.
    assert!(
        (num(gripper, "min_position") - 5.0).abs() < 1e-6,
        "{gripper}"
    );
}

/// A joint of a robot file, read here from the YAML on its own: name and
/// limits (deg).
struct Limits {
    name: String,
    v: f64,
    a: f64,
    j: Option<f64>,
}

fn yaml(path: &Path) -> serde_yaml::Value {
    let text = std::fs::read_to_string(path).expect("a shipped file");
    serde_yaml::from_str(&text).expect("YAML")
}

fn f(v: &serde_yaml::Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("a number: {v:?}"))
}

/// The robot's joints in file order.
fn robot_limits(robot: &serde_yaml::Value) -> Vec<Limits> {
    assert_eq!(robot["units"].as_str().unwrap_or("deg"), "deg");
    let mut out = Vec::new();
    for bus in robot["buses"].as_sequence().expect("buses") {
        for j in bus["joints"].as_sequence().expect("joints") {
            out.push(Limits {
                name: j["name"].as_str().expect("a name").to_string(),
                v: f(&j["max_velocity"]),
                a: f(&j["max_acceleration"]),
                j: j.get("max_jerk").map(f),
            });
        }
    }
    out
}

/// Every keyframe's full pose (deg, robot joint order): named poses looked
/// up, joints a keyframe leaves out carried over from the one before.
fn keyframe_poses(motion: &serde_yaml::Value, joints: &[Limits]) -> Vec<Vec<f64>> {
    let mut now: Vec<Option<f64>> = vec![None; joints.len()];
    let mut out = Vec::new();
    for k in motion["keyframes"].as_sequence().expect("keyframes") {
        let pose = match &k["pose"] {
            serde_yaml::Value::String(name) => &motion["poses"][name.as_str()],
            inline => inline,
        };
        for (key, value) in pose.as_mapping().expect("a pose is a mapping") {
            let name = key.as_str().expect("a joint name");
            let i = joints
                .iter()
                .position(|j| j.name == name)
                .unwrap_or_else(|| panic!("no joint {name}"));
            now[i] = Some(f(value));
        }
        out.push(
            now.iter()
                .map(|p| p.expect("the first keyframe names every joint"))
                .collect(),
        );
    }
    out
}

/// Every shipped motion plans, and its figures agree with what the files
/// say on their own:
/// - no joint leaves the range of its keyframes (rest-to-rest time-optimal
///   moves and the shape-preserving timed interpolation never overshoot);
/// - no peak exceeds the robot file's limits, and the fastest joint
///   reaches a good part of one (a plan that never moves would not);
/// - a timed motion lasts `repeat` times its last `at`; an untimed one at
///   least `repeat` times the sum over segments of the slowest joint's
///   distance over its velocity limit (no path can be faster).
#[test]
fn every_shipped_motion_plans() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/motions");
    let mut n = 0;
    for entry in std::fs::read_dir(dir).expect("configs/motions") {
        let path = entry.expect("entry").path();
        let v = plan_json(&path);
        let motion = yaml(&path);
        assert_eq!(motion["units"].as_str().unwrap_or("deg"), "deg");
        let robot_path = path.parent().expect("a directory").join(
            motion["robot"]
                .as_str()
                .expect("the motion names its robot"),
        );
        let joints = robot_limits(&yaml(&robot_path));
        // Keyframes in space (`tool`, `walk`, `body`) say no joint angles
        // in the file: their ranges and durations are tests/spatial's.
        let in_space = motion["keyframes"]
            .as_sequence()
            .expect("keyframes")
            .iter()
            .any(|k| ["tool", "walk", "body"].iter().any(|f| k.get(f).is_some()));
        let poses = if in_space {
            Vec::new()
        } else {
            keyframe_poses(&motion, &joints)
        };
        let repeat = motion["repeat"].as_f64().unwrap_or(1.0);
        let planned = v["joints"].as_array().expect("joints");
        assert_eq!(planned.len(), joints.len(), "{}", path.display());
        let mut fastest: f64 = 0.0;
        for (i, (j, p)) in joints.iter().zip(planned).enumerate() {
            assert_eq!(p["name"], j.name.as_str());
            let lo = poses.iter().map(|k| k[i]).fold(f64::INFINITY, f64::min);
            let hi = poses.iter().map(|k| k[i]).fold(f64::NEG_INFINITY, f64::max);
            let what = format!("{} {}: {p}", path.display(), j.name);
            if !in_space {
                assert!(
                    (num(p, "min_position") - lo).abs() < 1e-6,
                    "min {lo}, {what}"
                );
                assert!(
                    (num(p, "max_position") - hi).abs() < 1e-6,
                    "max {hi}, {what}"
                );
            }
            assert!(num(p, "peak_velocity") <= j.v * (1.0 + 1e-9), "{what}");
            assert!(num(p, "peak_acceleration") <= j.a * (1.0 + 1e-9), "{what}");
            if let Some(jerk) = j.j {
                assert!(num(p, "peak_jerk") <= jerk * (1.0 + 1e-9), "{what}");
            }
            fastest = fastest.max(num(p, "peak_velocity") / j.v);
        }
        assert!(fastest > 0.2, "{}: nothing moves fast", path.display());
        let duration = num(&v, "duration_s");
        let keyframes = motion["keyframes"].as_sequence().expect("keyframes");
        if in_space {
            assert!(duration > 0.0, "{}", path.display());
        } else if let Some(last) = keyframes.last().and_then(|k| k["at"].as_f64()) {
            assert!(
                (duration - repeat * last).abs() < 1e-6,
                "{}: {repeat} x {last} s, planned {duration} s",
                path.display()
            );
        } else {
            let pass: f64 = poses
                .windows(2)
                .map(|w| {
                    joints
                        .iter()
                        .enumerate()
                        .map(|(i, j)| (w[1][i] - w[0][i]).abs() / j.v)
                        .fold(0.0, f64::max)
                })
                .sum();
            assert!(
                duration >= repeat * pass - 1e-9,
                "{}: at least {repeat} x {pass} s, planned {duration} s",
                path.display()
            );
        }
        n += 1;
    }
    assert!(n >= 5);
}

#[test]
fn a_segment_beyond_a_limit_names_keyframe_joint_peak_and_limit() {
    // Half a second for 90 deg, under each kind of interpolation.
    let fast = "keyframes:\n  - {at: 0, pose: {a: 0}}\n  - {at: 0.5, pose: {a: 90}}\n";
    let m = motion(
        "too_fast",
        "m.yaml",
        &format!("robot: robot.yaml\ninterpolation: spline\n{fast}"),
    );
    let err = plan_error(&m);
    let want = format!("{}:5:5: keyframes[1]: joint `a`: ", m.display());
    says(
        &err,
        &[&want, "deg/s", "above the limit", "on_limit: stretch"],
    );

    // The default (shape-preserving) refuses it too: even stopping at the
    // keyframe needs 1.5 s (a trapezoid at 90 deg/s and 180 deg/s^2).
    let m3 = motion("too_fast", "m3.yaml", &format!("robot: robot.yaml\n{fast}"));
    let err = plan_error(&m3);
    says(
        &err,
        &["keyframes[1].at", "at least 1.500 s", "on_limit: stretch"],
    );

    // With `on_limit: stretch` the same motion plans, just slower.
    let m2 = motion(
        "too_fast",
        "m2.yaml",
        &format!("robot: robot.yaml\non_limit: stretch\n{fast}"),
    );
    let v = plan_json(&m2);
    assert!(num(&v, "duration_s") > 0.5);
    assert!(num(&v["joints"][0], "peak_velocity") <= 90.0 * (1.0 + 1e-6));
}

#[test]
fn format_errors_have_file_line_and_column() {
    let m = motion(
        "format",
        "m.yaml",
        "robot: robot.yaml\nkeyframes:\n  - pose: {a: 0}\n  - pose: {a: 200}\n",
    );
    let want = format!(
        "{}:4:15: keyframes[1].pose.a: keyframe 1: 200 deg is outside the limits of joint `a` [-100, 100] deg (the upper limit comes from the robot file's `min`/`max`)",
        m.display()
    );
    says(&plan_error(&m), &[&want]);
}

#[test]
fn robot_override_and_text_output() {
    let m = motion(
        "override",
        "m.yaml",
        "robot: nowhere.yaml\nkeyframes:\n  - pose: {a: 0}\n  - pose: {a: 90}\n",
    );
    let r = m.with_file_name("robot.yaml");
    let out = servobus_ok(&["plan", arg(&m), "--robot", arg(&r)]);
    says(&stdout(&out), &["1.500 s at 100 Hz", "segments"]);
}

#[test]
fn plot_draws_titles_axes_and_a_legend() {
    let svg = Path::new(env!("CARGO_TARGET_TMPDIR")).join("plan_cli/arm-wave.svg");
    let _ = std::fs::remove_file(&svg);
    servobus_ok(&["plan", "configs/motions/arm-wave.yaml", "--plot", arg(&svg)]);
    let text = std::fs::read_to_string(&svg).expect("the SVG was written");
    assert!(text.starts_with("<svg"), "not an SVG");
    says(
        &text,
        &[
            "arm-wave.yaml",
            "Position of every joint",
            "Velocity of every joint",
            "time (s)",
            "position (deg)",
            "velocity (deg/s)",
            "shoulder_pan",
            "gripper",
        ],
    );
}

/// The segment list gives a keyframe's written time to the millisecond
/// (`at: 1.5`); a time the planner chose for the keyframe before a move in
/// space (an f64 of 16 digits) is not given as an `at:` at all.
#[test]
fn keyframe_times_are_printed_to_the_millisecond() {
    // Written times, to the millisecond.
    let out = stdout(&servobus_ok(&["plan", "arm-pick-place"]));
    let times: Vec<&str> = out
        .split(", at: ")
        .skip(1)
        .filter_map(|rest| rest.split(')').next())
        .collect();
    assert!(
        !times.is_empty(),
        "arm-pick-place has timed keyframes: {out}"
    );
    for t in &times {
        let decimals = t.split_once('.').map_or(0, |(_, d)| d.len());
        assert!(decimals <= 3, "`at: {t}` in {out}");
        assert!(t.parse::<f64>().is_ok(), "`at: {t}` in {out}");
    }
    // The times the planner chose for arm-line's keyframes before its
    // moves in space are the arrivals the rows show, not `at:`s of the
    // file; its tool keyframe is called one.
    let out = stdout(&servobus_ok(&["plan", "arm-line"]));
    assert!(!out.contains(", at: "), "{out}");
    assert!(out.contains(" tool pose "), "{out}");
}
