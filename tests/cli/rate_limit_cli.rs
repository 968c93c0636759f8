//! A maximum rate that is one: `budget` fails when the rate does not fit,
//! `play` and `bench` refuse it unless round-robin reads are allowed, and
//! every command names the same (floored) maximum.
//!
//! The SO-101 arm's full cycle at 1 Mbps is 880 us on the wire plus 6 x 50 us
//! of turnaround = 1180 us, plus on the built-in simulator the
//! pseudo-terminal's 60 us per round trip and 8 us per reply: 1288 us, at
//! most 776.4 Hz (776 Hz floored). With 490 us of adapter latency it is
//! 1778 us, so its maximum is 562.4 Hz: 562 Hz is the fastest whole rate
//! that fits.

use crate::common;

use std::path::{Path, PathBuf};

use common::{arg, edited, exited, json, repo, says, scratch, servobus, write_file};

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
    write_file(&scratch(name), "arm.yaml", &out)
}

/// arm-wave for the robot at `robot`.
fn wave_for(robot: &Path) -> PathBuf {
    let src = std::fs::read_to_string(repo("configs/motions/arm-wave.yaml")).expect("wave");
    let body: String = src
        .lines()
        .filter(|l| !l.starts_with("robot:"))
        .map(|l| format!("{l}\n"))
        .collect();
    let dir = robot.parent().expect("a folder");
    write_file(
        dir,
        "wave.yaml",
        &format!("robot: {}\n{body}", robot.display()),
    )
}

#[test]
fn budget_exits_1_when_the_rate_does_not_fit_in_text_and_json() {
    exited(
        &servobus(&["budget", "--robot", "so101", "--rate", "776"]),
        0,
    );
    for json in [false, true] {
        let mut args = vec!["budget", "--robot", "so101", "--rate", "777"];
        if json {
            args.push("--json");
        }
        let out = servobus(&args);
        let (stdout, _) = exited(&out, 1);
        if json {
            assert_eq!(common::json(&out)["buses"][0]["feasible"], false);
        } else {
            says(&stdout, &["lower the rate to 776 Hz"]);
        }
    }
}

#[test]
fn budget_accepts_a_round_robin_the_robot_file_allows() {
    let robot = slow_arm("rr-budget", "round_robin: true");
    // 900 Hz (1111 us): one servo a cycle takes 26 + 9 + 8 bytes (430 us),
    // 50 us of turnaround, 490 us of latency and 60 + 8 us of the pty's
    // overhead = 1038 us.
    let out = servobus(&["budget", "--robot", arg(&robot), "--rate", "900", "--json"]);
    exited(&out, 0);
    let v = json(&out);
    assert_eq!(v["buses"][0]["feasible"], false);
    assert_eq!(v["buses"][0]["round_robin"], true);
    assert!(v["buses"][0]["read_every"].as_u64().expect("read_every") > 1);
}

#[test]
fn budget_and_play_name_the_same_floored_maximum() {
    let robot = slow_arm("rr-floor", "");
    let wave = wave_for(&robot);
    let budget = common::stdout(&servobus(&["budget", "--robot", arg(&robot)]));
    says(&budget, &["maximum rate 562 Hz"]);

    let wave = arg(&wave);
    let (fits, _) = exited(&servobus(&["play", wave, "--fast", "--rate", "562"]), 0);
    says(&fits, &["(max 562 Hz)"]);

    let (_, err) = exited(&servobus(&["play", wave, "--fast", "--rate", "563"]), 2);
    says(
        &err,
        &[
            "fastest rate that fits is 562 Hz",
            "--round-robin",
            "round_robin: true",
        ],
    );
}

#[test]
fn play_refuses_a_rate_above_the_maximum_unless_round_robin_is_allowed() {
    // 1500 Hz (666 us): only one servo a cycle fits, 26 + 9 + 8 bytes
    // (430 us) + 50 us of turnaround + 60 + 8 us of the pty's overhead
    // (548 us); two would take 696 us.
    let refused = servobus(&["play", "arm-wave", "--fast", "--rate", "1500"]);
    let (_, err) = exited(&refused, 2);
    says(&err, &["fastest rate that fits is 776 Hz", "--round-robin"]);

    let out = servobus(&[
        "play",
        "arm-wave",
        "--fast",
        "--json",
        "--rate",
        "1500",
        "--round-robin",
    ]);
    exited(&out, 0);
    let v = json(&out);
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
    let (_, err) = exited(&out, 2);
    says(&err, &["776 Hz"]);
}

#[test]
fn bench_refuses_a_robot_rate_above_the_maximum() {
    let fast = edited("configs/robots/so101.yaml", &[("rate: 200", "rate: 1000")]);
    let path = write_file(&scratch("rr-bench"), "fast.yaml", &fast);
    let bench = ["bench", "--robot", arg(&path), "--seconds", "0.1", "--json"];
    let (_, err) = exited(&servobus(&bench), 2);
    says(&err, &["fastest rate that fits is 776 Hz", "--round-robin"]);
    exited(&servobus(&[&bench[..], &["--round-robin"]].concat()), 0);
}

#[test]
fn latency_us_is_a_number_or_auto() {
    // so101 ships `auto`.
    let bad = edited(
        "configs/robots/so101.yaml",
        &[("latency_us: auto", "latency_us: fast")],
    );
    let auto = common::stdout(&servobus(&["budget", "--robot", "so101"]));
    says(&auto, &["adapter latency auto"]);

    let path = write_file(&scratch("latency-word"), "arm.yaml", &bad);
    let (_, err) = exited(&servobus(&["budget", "--robot", arg(&path)]), 2);
    says(&err, &["latency_us", "`auto`"]);
}
