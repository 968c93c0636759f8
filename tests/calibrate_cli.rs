//! `servobus calibrate` on the command line, and `play`/`bench` refusing
//! to move servos that do not match the robot's calibration.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::{repo, scratch, Sim, BIN};

const LEROBOT: &str = "crates/runtime/tests/data/so101-lerobot.json";

fn run(args: &[&str], paths: &[&Path]) -> Output {
    let mut cmd = Command::new(BIN);
    cmd.args(args).current_dir(env!("CARGO_MANIFEST_DIR"));
    for p in paths {
        cmd.arg(p);
    }
    cmd.output().expect("servobus runs")
}

/// The SO-101 robot file, copied to `dir` with `calibration: FILE` added.
fn robot_naming(dir: &Path, calibration: &str) -> PathBuf {
    let text = std::fs::read_to_string(repo("configs/robots/so101.yaml")).expect("so101");
    let path = dir.join("so101.yaml");
    std::fs::write(&path, format!("calibration: {calibration}\n{text}")).expect("write robot");
    path
}

/// A servo register read through `servobus read`.
fn read(port: &str, id: &str, register: &str) -> i64 {
    let v = common::servobus_json(&["read", "--port", port, "--id", id, register, "--json"]);
    v["value"]
        .as_i64()
        .unwrap_or_else(|| panic!("a value in {v}"))
}

fn assert_refused(out: &Output, why: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "refused: {err}");
    assert!(err.contains(why), "{err:?} says {why:?}");
    assert!(err.contains("nothing was moved"), "{err}");
    assert!(
        err.contains("servobus calibrate --robot"),
        "says what to run: {err}"
    );
}

#[test]
fn a_lerobot_file_goes_through_calibrate_and_comes_back_identical() {
    let dir = scratch("calib-lerobot");
    let cal = dir.join("arm.calibration.yaml");
    let json = dir.join("back.json");
    let out = run(
        &[
            "calibrate",
            "--robot",
            "configs/robots/so101.yaml",
            "--from-lerobot",
            LEROBOT,
            "-o",
        ],
        &[&cal],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = run(
        &[
            "calibrate",
            "--robot",
            "configs/robots/so101.yaml",
            "--to-lerobot",
        ],
        &[&json, Path::new("--calibration"), &cal],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let original = std::fs::read_to_string(repo(LEROBOT)).expect("fixture");
    assert_eq!(std::fs::read_to_string(&json).expect("exported"), original);
}

#[test]
fn play_and_bench_refuse_a_missing_calibration_before_moving_anything() {
    let dir = scratch("calib-missing");
    let robot = robot_naming(&dir, "arm.calibration.yaml");
    let sim = Sim::start(&dir);
    let port = sim.port().to_owned();
    let before = read(&port, "2", "present_position");
    let out = run(
        &[
            "play",
            "configs/motions/arm-wave.yaml",
            "--port",
            &port,
            "--robot",
        ],
        &[&robot],
    );
    assert_refused(&out, "does not exist");
    let out = run(
        &["bench", "--seconds", "0.2", "--port", &port, "--robot"],
        &[&robot],
    );
    assert_refused(&out, "does not exist");
    // Torque was never switched on, and the joint is where it was.
    assert_eq!(read(&port, "2", "torque_enable"), 0);
    assert_eq!(read(&port, "2", "present_position"), before);
    // On the built-in simulator (no port) the same robot still plays.
    let out = run(
        &["plan", "configs/motions/arm-wave.yaml", "--robot"],
        &[&robot],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    sim.stop();
}

#[test]
fn play_refuses_servos_that_do_not_match_the_calibration() {
    let dir = scratch("calib-mismatch");
    // LeRobot's calibration of another arm: its servos hold homing offsets
    // that the simulated ones (offset 0) do not.
    let other = dir.join("other.calibration.yaml");
    let out = run(
        &[
            "calibrate",
            "--robot",
            "configs/robots/so101.yaml",
            "--from-lerobot",
            LEROBOT,
            "-o",
        ],
        &[&other],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let sim = Sim::start(&dir);
    let port = sim.port().to_owned();
    let out = run(
        &[
            "play",
            "configs/motions/arm-wave.yaml",
            "--port",
            &port,
            "--calibration",
        ],
        &[&other],
    );
    assert_refused(
        &out,
        "holds homing offset 0, the calibration was taken with -1389",
    );

    // Offsets that match, but a range the joint is nowhere near.
    let json = std::fs::read_to_string(repo(LEROBOT)).expect("fixture");
    let mut v: serde_json::Value = serde_json::from_str(&json).expect("json");
    for (_, m) in v.as_object_mut().expect("object").iter_mut() {
        m["homing_offset"] = 0.into();
    }
    v["shoulder_pan"]["range_min"] = 100.into();
    v["shoulder_pan"]["range_max"] = 900.into();
    let moved = dir.join("moved.json");
    std::fs::write(&moved, v.to_string()).expect("write json");
    let far = dir.join("far.calibration.yaml");
    let out = run(
        &[
            "calibrate",
            "--robot",
            "configs/robots/so101.yaml",
            "--from-lerobot",
        ],
        &[&moved, Path::new("-o"), &far],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = run(
        &[
            "play",
            "configs/motions/arm-wave.yaml",
            "--port",
            &port,
            "--calibration",
        ],
        &[&far],
    );
    assert_refused(&out, "far outside its calibrated range");
    assert_eq!(read(&port, "1", "torque_enable"), 0);
    sim.stop();
}
