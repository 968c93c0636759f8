//! Output reads as sentences with units: aligned tables for long joint
//! names, a meaningful jerk column without a jerk limit, and examples that
//! print no `Debug` forms (`Some(..)`, `Completed`, `Read { .. }`).

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::{scratch, servobus};

const LONG: &str = "left_front_knee_flexion"; // 23 characters

fn robot(dir: &Path) -> PathBuf {
    let p = dir.join("robot.yaml");
    let text = format!(
        "name: long\nbuses:\n  - name: bus\n    joints:\n\
         \x20     - {{name: {LONG}, id: 1, model: sts3215, min: -90, max: 90, max_velocity: 180, max_acceleration: 900}}\n\
         \x20     - {{name: hip, id: 2, model: sts3215, min: -90, max: 90, max_velocity: 180, max_acceleration: 900, max_jerk: 9000}}\n"
    );
    std::fs::write(&p, text).expect("robot");
    let m = dir.join("m.yaml");
    std::fs::write(
        &m,
        format!("robot: robot.yaml\nkeyframes:\n  - pose: {{{LONG}: 0, hip: 0}}\n  - pose: {{{LONG}: 30, hip: -20}}\n"),
    )
    .expect("motion");
    m
}

fn stdout(o: &Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Where each whitespace-separated column of `line` ends.
fn column_ends(line: &str) -> Vec<usize> {
    let b = line.as_bytes();
    (0..b.len())
        .filter(|&i| b[i] != b' ' && (i + 1 == b.len() || b[i + 1] == b' '))
        .map(|i| i + 1)
        .collect()
}

#[test]
fn the_play_report_aligns_long_joint_names() {
    let dir = scratch("long-names");
    let m = robot(&dir);
    let out = stdout(&servobus(&["play", m.to_str().expect("utf-8"), "--fast"]));
    let header = out
        .lines()
        .find(|l| l.trim_start().starts_with("joint ") && l.contains("rms"))
        .unwrap_or_else(|| panic!("report header in {out}"));
    let want = column_ends(header);
    for name in [LONG, "hip"] {
        let row = out
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{name} ")))
            .unwrap_or_else(|| panic!("{name} row in {out}"));
        // Name, rms and max end where the header's joint, rms and max end
        // (the header's name column ends at `joint`, the row's at the name,
        // so compare the number columns).
        assert_eq!(&column_ends(row)[1..3], &want[1..3], "{header}\n{row}");
    }
}

#[test]
fn plan_says_when_a_joint_has_no_jerk_limit() {
    let dir = scratch("no-jerk");
    let m = robot(&dir);
    let out = stdout(&servobus(&["plan", m.to_str().expect("utf-8")]));
    let row = out
        .lines()
        .find(|l| l.starts_with(LONG))
        .unwrap_or_else(|| panic!("{out}"));
    assert!(row.trim_end().ends_with("no limit"), "{row}");
    assert!(!out.contains("steps"), "{out}");
    let hip = out.lines().find(|l| l.starts_with("hip ")).expect("hip");
    let jerk: f64 = hip
        .split_whitespace()
        .last()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("a number: {hip}"));
    assert!(jerk > 0.0 && jerk <= 9000.0, "{hip}");
}

/// An example's binary, built on demand (`cargo test` builds examples, a
/// filtered run may not have).
fn example(name: &str) -> PathBuf {
    let built = Command::new(env!("CARGO"))
        // `--workspace`: the feature set of `cargo test --workspace`, which
        // has built the examples already, so this is a no-op after it.
        .args([
            "build",
            "--offline",
            "--quiet",
            "--workspace",
            "--example",
            name,
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .status()
        .expect("cargo runs");
    assert!(built.success());
    let exe = std::env::current_exe().expect("test exe");
    let profile_dir = exe.ancestors().nth(2).expect("target/<profile>");
    let debug = profile_dir
        .with_file_name("debug")
        .join("examples")
        .join(name);
    assert!(debug.exists(), "{}", debug.display());
    debug
}

fn run(exe: &Path, args: &[&str]) -> Output {
    Command::new(exe)
        .args(args)
        .current_dir(std::env::temp_dir())
        .output()
        .expect("example runs")
}

fn no_debug_forms(text: &str) {
    for form in [
        "Some(",
        "None",
        "Completed",
        "Read {",
        "Error: ",
        "path: \"",
    ] {
        assert!(!text.contains(form), "{form:?} in {text}");
    }
}

#[test]
fn examples_print_sentences_not_debug() {
    let play = example("play_motion");
    let help = run(&play, &["--help"]);
    assert!(help.status.success());
    assert!(String::from_utf8_lossy(&help.stdout).starts_with("usage: play_motion"));
    let missing = run(&play, &["nothere.yaml"]);
    assert_eq!(missing.status.code(), Some(1));
    let err = String::from_utf8_lossy(&missing.stderr).into_owned();
    assert!(
        err.starts_with("error: nothere.yaml: cannot read: no such file"),
        "{err}"
    );
    no_debug_forms(&err);
    // From another directory, by name.
    let out = stdout(&run(&play, &["arm-wave"]));
    assert!(
        out.contains("arm-wave on so101") && out.contains(" deg"),
        "{out}"
    );
    no_debug_forms(&out);

    let live = stdout(&run(&example("live_errors"), &["scs-mini-nod"]));
    assert!(live.contains("the motion played to its end"), "{live}");
    no_debug_forms(&live);

    let stream = stdout(&run(&example("stream_trajectory"), &[]));
    assert!(stream.contains("ends at tick 20"), "{stream}");
    no_debug_forms(&stream);

    let jitter = stdout(&run(
        &example("loop_jitter"),
        &["--rate", "200", "--seconds", "0.1", "--core", "0"],
    ));
    assert!(jitter.contains("pinned to core 0"), "{jitter}");
    no_debug_forms(&jitter);
}

#[test]
fn a_run_too_short_to_identify_the_lag_does_not_suggest_a_lead_for_the_robot_file() {
    // 0.15 s of a 1 deg move: too little motion to identify the lag; the
    // lead in force is the servos' response lag, and the report says so
    // instead of offering it as a measured `lead_ms`.
    let dir = scratch("short-lead");
    let m = dir.join("short.yaml");
    std::fs::write(
        &m,
        "robot: so101\nunits: deg\nkeyframes:\n\
         \x20 - pose: {shoulder_pan: 0, shoulder_lift: -90, elbow_flex: 90, wrist_flex: 45, wrist_roll: 0, gripper: 10}\n\
         \x20 - pose: {shoulder_pan: 1}\n",
    )
    .expect("motion");
    let short = stdout(&servobus(&["play", "--fast", common::arg(&m)]));
    assert!(
        short.contains("too little motion to identify it"),
        "{short}"
    );
    assert!(!short.contains("in the robot file applies it"), "{short}");
    // The wave moves long enough: the identified lead is offered.
    let wave = stdout(&servobus(&["play", "--fast", "arm-wave"]));
    assert!(
        wave.contains("identified while moving (`lead_ms: "),
        "{wave}"
    );
}
