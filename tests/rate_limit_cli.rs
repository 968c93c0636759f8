//! A maximum rate that is one: `budget` fails when the rate does not fit,
//! `play` and `bench` refuse it unless round-robin reads are allowed, and
//! every command names the same (floored) maximum.
//!
//! The SO-101 arm's full cycle at 1 Mbps is 880 us on the wire plus 6 x 50 us
//! of turnaround = 1180 us; with 490 us of adapter latency it is 1670 us, so
//! its maximum is 598.8 Hz: 598 Hz is the fastest whole rate that fits.

mod common;

use std::path::PathBuf;
use std::process::Output;

use common::{repo, scratch, servobus};

fn text(out: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// so101 with 490 us of adapter latency (and `extra` appended to its bus).
fn slow_arm(name: &str, extra: &str) -> PathBuf {
    let src = std::fs::read_to_string(repo("configs/robots/so101.yaml")).expect("so101");
    let mut out = String::new();
    for line in src.lines() {
        if line.trim_start().starts_with("latency_us:") {
            out.push_str("    latency_us: 490\n");
            if !extra.is_empty() {
                out.push_str(&format!("    {extra}\n"));
            }
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    let path = scratch(name).join("arm.yaml");
    std::fs::write(&path, out).expect("write robot");
    path
}

/// arm-wave for the robot at `robot`.
fn wave_for(robot: &std::path::Path) -> PathBuf {
    let src = std::fs::read_to_string(repo("configs/motions/arm-wave.yaml")).expect("wave");
    let body: String = src
        .lines()
        .filter(|l| !l.starts_with("robot:"))
        .map(|l| format!("{l}\n"))
        .collect();
    let path = robot.with_file_name("wave.yaml");
    std::fs::write(&path, format!("robot: {}\n{body}", robot.display())).expect("write motion");
    path
}

#[test]
fn budget_exits_1_when_the_rate_does_not_fit_in_text_and_json() {
    let ok = servobus(&["budget", "--robot", "so101", "--rate", "847"]);
    assert_eq!(ok.status.code(), Some(0), "{:?}", text(&ok));
    for json in [false, true] {
        let mut args = vec!["budget", "--robot", "so101", "--rate", "848"];
        if json {
            args.push("--json");
        }
        let out = servobus(&args);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {:?}", text(&out));
        if json {
            let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
            assert_eq!(v["buses"][0]["feasible"], false);
        } else {
            assert!(text(&out).0.contains("lower the rate to 847 Hz"));
        }
    }
}

#[test]
fn budget_accepts_a_round_robin_the_robot_file_allows() {
    let robot = slow_arm("rr-budget", "round_robin: true");
    let robot = robot.to_str().expect("utf-8 path");
    let out = servobus(&["budget", "--robot", robot, "--rate", "1000", "--json"]);
    assert_eq!(out.status.code(), Some(0), "{:?}", text(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(v["buses"][0]["feasible"], false);
    assert_eq!(v["buses"][0]["round_robin"], true);
    assert!(v["buses"][0]["read_every"].as_u64().expect("read_every") > 1);
}

#[test]
fn budget_and_play_name_the_same_floored_maximum() {
    let robot = slow_arm("rr-floor", "");
    let wave = wave_for(&robot);
    let robot = robot.to_str().expect("utf-8 path");
    let (budget, _) = text(&servobus(&["budget", "--robot", robot]));
    assert!(budget.contains("maximum rate 598 Hz"), "{budget}");

    let wave = wave.to_str().expect("utf-8 path");
    let fits = servobus(&["play", wave, "--fast", "--rate", "598"]);
    assert_eq!(fits.status.code(), Some(0), "{:?}", text(&fits));
    assert!(text(&fits).0.contains("(max 598 Hz)"), "{:?}", text(&fits));

    let above = servobus(&["play", wave, "--fast", "--rate", "599"]);
    assert_eq!(above.status.code(), Some(2), "{:?}", text(&above));
    let (_, err) = text(&above);
    assert!(err.contains("fastest rate that fits is 598 Hz"), "{err}");
    assert!(err.contains("--round-robin"), "{err}");
    assert!(err.contains("round_robin: true"), "{err}");
}

#[test]
fn play_refuses_a_rate_above_the_maximum_unless_round_robin_is_allowed() {
    let refused = servobus(&["play", "arm-wave", "--fast", "--rate", "2000"]);
    assert_eq!(refused.status.code(), Some(2), "{:?}", text(&refused));
    let (_, err) = text(&refused);
    assert!(err.contains("fastest rate that fits is 847 Hz"), "{err}");
    assert!(err.contains("--round-robin"), "{err}");

    let out = servobus(&[
        "play",
        "arm-wave",
        "--fast",
        "--json",
        "--rate",
        "2000",
        "--round-robin",
    ]);
    assert_eq!(out.status.code(), Some(0), "{:?}", text(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(v["finish"], "completed");
    assert_eq!(v["buses"][0]["read_every"], 6, "{v:#}");
}

#[test]
fn a_rate_no_round_robin_can_run_names_the_fastest_rate() {
    let out = servobus(&[
        "play",
        "arm-wave",
        "--fast",
        "--rate",
        "5000",
        "--round-robin",
    ]);
    assert_eq!(out.status.code(), Some(2), "{:?}", text(&out));
    let (_, err) = text(&out);
    assert!(err.contains("847 Hz"), "{err}");
}

#[test]
fn bench_refuses_a_robot_rate_above_the_maximum() {
    let src = std::fs::read_to_string(repo("configs/robots/so101.yaml")).expect("so101");
    let fast = src.replacen("rate: 200", "rate: 1000", 1);
    assert_ne!(fast, src, "so101.yaml sets `rate: 200`");
    let dir = scratch("rr-bench");
    let path = dir.join("fast.yaml");
    std::fs::write(&path, fast).expect("write robot");
    let path = path.to_str().expect("utf-8 path");
    let out = servobus(&["bench", "--robot", path, "--seconds", "0.1", "--json"]);
    assert_eq!(out.status.code(), Some(2), "{:?}", text(&out));
    let (_, err) = text(&out);
    assert!(err.contains("fastest rate that fits is 847 Hz"), "{err}");
    assert!(err.contains("--round-robin"), "{err}");

    let ok = servobus(&[
        "bench",
        "--robot",
        path,
        "--seconds",
        "0.1",
        "--json",
        "--round-robin",
    ]);
    assert_eq!(ok.status.code(), Some(0), "{:?}", text(&ok));
}

#[test]
fn latency_us_is_a_number_or_auto() {
    let src = std::fs::read_to_string(repo("configs/robots/so101.yaml")).expect("so101");
    assert!(src.contains("latency_us: auto"), "so101 ships `auto`");
    let (text_auto, _) = text(&servobus(&["budget", "--robot", "so101"]));
    assert!(text_auto.contains("adapter latency auto"), "{text_auto}");

    let bad = src.replacen("latency_us: auto", "latency_us: fast", 1);
    let path = scratch("latency-word").join("arm.yaml");
    std::fs::write(&path, bad).expect("write robot");
    let out = servobus(&["budget", "--robot", path.to_str().expect("utf-8")]);
    assert_eq!(out.status.code(), Some(2), "{:?}", text(&out));
    let (_, err) = text(&out);
    assert!(err.contains("latency_us"), "{err}");
    assert!(err.contains("`auto`"), "{err}");
}
