//! End to end: `servobus play --fast` on every motion in `configs/`, the
//! report's figures checked; a bad motion file refused before anything
//! moves; the CSV log and the plot written.

use crate::common;

use common::{arg, repo, scratch, servobus_json, write_file, Sim};
use serde_json::Value;

/// `servobus play --fast --json ARGS`, which must succeed: its report.
fn play_json(args: &[&str]) -> Value {
    servobus_json(&[&["play", "--fast", "--json"], args].concat())
}

/// Checks what every clean run on the simulator must show: it completed, at
/// exactly the requested rate, with nothing lost, clamped or overrun, and a
/// tracking error per joint within `max_error` (in the motion's units).
fn check_clean(report: &Value, joints: usize, max_error: f64) {
    assert_eq!(report["finish"], "completed", "{report:#}");
    assert!(report["cycles"].as_u64().expect("cycles") > 50);
    let planned = report["planned_rate_hz"].as_f64().expect("planned rate");
    let achieved = report["achieved_rate_hz"].as_f64().expect("achieved rate");
    assert!(
        (achieved - planned).abs() < 1e-6 * planned,
        "achieved {achieved} Hz, requested {planned} Hz"
    );
    for field in [
        "overruns",
        "timeouts",
        "missed_replies",
        "clamps",
        "telemetry_dropped",
    ] {
        assert_eq!(report[field], 0, "{field} in {report:#}");
    }
    for q in ["p50", "p99", "max"] {
        assert_eq!(report["period_error_us"][q], 0.0, "virtual time is exact");
    }
    let list = report["joints"].as_array().expect("joints");
    assert_eq!(list.len(), joints);
    for j in list {
        let rms = j["rms_error"].as_f64().expect("rms");
        let max = j["max_error"].as_f64().expect("max");
        // An RMS never exceeds the maximum; and a simulated servo lags its
        // goals, so a run reporting no error at all measured nothing.
        assert!(rms > 1e-3 && rms <= max + 1e-12, "{j}");
        assert!(
            max < max_error,
            "{} tracks within {max_error}: {j}",
            j["name"]
        );
    }
    assert!(report["fault"].is_null());
}

#[test]
fn every_motion_in_configs_plays_cleanly_on_its_robot() {
    let mut played = 0;
    let mut entries: Vec<_> = std::fs::read_dir(repo("configs/motions"))
        .expect("configs/motions")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
        .collect();
    entries.sort();
    for path in entries {
        let name = arg(&path);
        let report = play_json(&[name]);
        // Joint counts of the robots the motions name.
        let joints = if name.contains("hexapod") {
            18
        } else if name.contains("scs") {
            4
        } else {
            6
        };
        // The README's figures: the STS3215 arms and hexapods track within
        // 3 degrees (worst shipped motion, hexapod-dance: 2.72), the
        // SCS0009, with 0.29 deg ticks and a soft position loop, within 6
        // (scs-mini-nod: 5.29). Virtual time makes these exact repeats.
        let bound = if name.contains("scs") { 6.0 } else { 3.0 };
        check_clean(&report, joints, bound);
        played += 1;
    }
    assert!(played >= 5, "only {played} motions found");
}

#[test]
fn the_hexapod_plays_on_two_buses_in_step() {
    let report = play_json(&[
        "configs/motions/hexapod-tripod.yaml",
        "--robot",
        "configs/robots/hexapod-2bus.yaml",
    ]);
    check_clean(&report, 18, 3.0);
    let buses = report["buses"].as_array().expect("buses");
    assert_eq!(buses.len(), 2);
    assert_eq!(
        buses[0]["cycles"], buses[1]["cycles"],
        "the buses run in step"
    );
}

#[test]
fn log_and_plot_are_written() {
    let dir = scratch("play-log");
    let log = dir.join("wave.csv");
    let plot = dir.join("wave.svg");
    let report = play_json(&[
        "configs/motions/arm-wave.yaml",
        "--log",
        arg(&log),
        "--plot",
        arg(&plot),
    ]);
    let cycles = report["cycles"].as_u64().expect("cycles");

    let text = std::fs::read_to_string(&log).expect("log written");
    let mut lines = text.lines();
    let header = lines.next().expect("header");
    assert!(header.starts_with("time_s,bus,cycle,joint,commanded_deg,planned_deg,measured_deg"));
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len() as u64, cycles * 6, "one row per cycle and joint");
    assert!(rows.iter().any(|r| r.contains(",wrist_roll,")));

    let svg = std::fs::read_to_string(&plot).expect("plot written");
    for text in [
        "arm-wave.yaml on so101",
        "shoulder_pan",
        "gripper",
        "time (s)",
        "position (deg)",
        "tracking error",
        "measured",
    ] {
        assert!(svg.contains(text), "the plot shows {text:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bad_motion_file_names_the_place_and_moves_nothing() {
    let dir = scratch("play-bad");
    let robot = repo("configs/robots/so101.yaml");
    let motion = write_file(
        &dir,
        "bad.yaml",
        &format!(
            "robot: {}\nunits: deg\nkeyframes:\n  - pose: {{shoulder_pan: 0}}\n  - pose: {{shoulder_pan: 500}}\n",
            robot.display()
        ),
    );

    // On a simulated arm served on a pty, exactly as on real servos.
    let sim = Sim::start(&dir);
    let out = common::servobus(&["play", arg(&motion), "--port", sim.port()]);
    assert_eq!(out.status.code(), Some(2), "an input error");
    let err = common::stderr(&out);
    let place = format!("{}:5:26:", motion.display());
    assert!(err.contains(&place), "{err:?} names {place}");
    assert!(err.contains("shoulder_pan") && err.contains("500"), "{err}");
    assert!(out.stdout.is_empty(), "nothing planned, nothing played");

    // Torque was never enabled and no goal was ever written.
    for (register, value) in [("torque_enable", 0), ("goal_position", 2048)] {
        assert_eq!(sim.read("1", register), value, "{register} untouched");
    }
    sim.stop();
    let _ = std::fs::remove_dir_all(&dir);
}

/// Built without the `rerun` feature, every command that records refuses
/// `--rerun` before anything moves, and says how to build with it.
#[cfg(not(feature = "rerun"))]
#[test]
fn rerun_flags_without_the_feature_are_refused_before_anything_moves() {
    let dir = common::scratch("play-rerun-refused");
    let rrd = dir.join("x.rrd");
    let runs: [&[&str]; 3] = [
        &["play", "arm-wave", "--fast", "--rerun", common::arg(&rrd)],
        &["plan", "arm-wave", "--rerun", common::arg(&rrd)],
        &["play", "arm-wave", "--fast", "--rerun-connect"],
    ];
    for args in runs {
        let out = common::servobus(args);
        let text = common::error(&out, 2);
        assert!(
            text.contains("built without Rerun: cargo install --path . --features rerun"),
            "{args:?}: {text}"
        );
        assert!(!rrd.exists(), "{args:?} wrote the recording");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
