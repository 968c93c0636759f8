//! The simulator twin of `docs/first-arm.md`, end to end, as its table
//! says: a carelessly assembled arm (`--unit 7`) with the walkthrough's
//! scripted hand, then `init`, `doctor` (every fix it prints run as
//! printed), `calibrate`, the calibration named in `robot.yaml`, `doctor`
//! again (exit 0), `teach --yes`, and `play` of what was taught. The truth
//! the simulator writes must pass within 1 deg of every taught pose.
//!
//! The hand works on the simulator's clock: the rest until 45 s, the
//! calibration until 80 s, the poses to teach until 94 s. This test takes
//! about as long (some 110 s), in wall-clock time.

use crate::common;

use std::path::Path;
use std::process::{Command, Output, Stdio};

use common::{arg, read_truth, scratch, stderr, stdout, Sim, BIN};

/// Runs `servobus ARGS` in `dir` with no terminal.
fn run_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .output()
        .expect("servobus runs")
}

/// Doctor's findings (`--json`) in `dir`: its exit code and the commands
/// it printed.
fn doctor(dir: &Path, port: &str) -> (i32, Vec<String>, serde_json::Value) {
    let out = run_in(
        dir,
        &["doctor", "--robot", "robot.yaml", "--port", port, "--json"],
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("doctor --json: {e}: {}{}", stdout(&out), stderr(&out)));
    let commands = report["buses"]
        .as_array()
        .into_iter()
        .flatten()
        .flat_map(|b| b["findings"].as_array().into_iter().flatten())
        .filter_map(|f| f["command"].as_str().map(str::to_owned))
        .filter(|c| !c.is_empty())
        .collect();
    (out.status.code().unwrap_or(-1), commands, report)
}

/// Runs a command doctor printed, exactly as printed (its words split on
/// spaces, `servobus` being the binary under test), in `dir`.
fn run_as_printed(dir: &Path, command: &str) -> Output {
    let words: Vec<&str> = command.split_whitespace().collect();
    assert_eq!(
        words.first(),
        Some(&"servobus"),
        "a servobus command: {command}"
    );
    common::succeeded(run_in(dir, &words[1..]), &words[1..])
}

#[test]
#[ignore = "a person's part in real time, about 2 minutes: `cargo test --test cli -- --ignored` (the gate runs it)"]
fn the_first_arm_walkthrough_runs_on_its_simulator_twin() {
    let dir = scratch("first-arm");
    let arm = dir.join("arm");
    // 1. init (before the simulator: the twin serves the robot file init
    // wrote, as a user's own arm would be).
    let out = run_in(&dir, &["init", "arm"]);
    assert!(out.status.success(), "init: {}", stderr(&out));
    let robot = arm.join("robot.yaml");
    assert!(robot.is_file(), "init wrote robot.yaml");

    // 0. The twin: a random unit with the walkthrough's hand.
    let truth = arm.join("truth.csv");
    let sim = Sim::start_robot(
        &arm,
        &robot,
        6,
        &[
            "--unit",
            "7",
            "--hand",
            "so101-first-arm-hand",
            "--truth",
            arg(&truth),
        ],
    );
    let port = sim.port().to_owned();

    // 2. doctor: every fix it prints runs as printed. The calibration it
    // asks for is step 3, which the hand drives from 45 s.
    let (code, commands, report) = doctor(&arm, &port);
    assert!(code == 1 || code == 2, "a new arm has findings: {report}");
    let text = report.to_string();
    assert!(text.contains("calibrate first"), "{text}");
    assert!(
        !text.contains("into its limits by hand"),
        "no limits before calibrating: {text}"
    );
    let (calibrate, fixes): (Vec<String>, Vec<String>) = commands
        .into_iter()
        .partition(|c| c.starts_with("servobus calibrate"));
    assert_eq!(calibrate.len(), 1, "one calibrate command: {calibrate:?}");
    for fix in &fixes {
        run_as_printed(&arm, fix);
    }
    assert!(
        sim.started.elapsed().as_secs_f64() < 45.0,
        "init, doctor and its fixes took past 45 s: the hand has started"
    );

    // 3. calibrate, as doctor printed it (no terminal: each step ends when
    // the arm has moved and been held still).
    let out = run_as_printed(&arm, &calibrate[0]);
    let said = stdout(&out);
    assert!(said.contains("4. Done"), "{said}");
    assert!(
        said.contains("across the seam"),
        "unit 7 crosses the seam: {said}"
    );
    assert!(!said.contains('\x1b'), "no escape codes without a terminal");
    // Doctor names the file the robot file's comment gives.
    assert!(
        calibrate[0].ends_with("-o my-arm.calibration.yaml"),
        "{calibrate:?}"
    );
    assert!(arm.join("my-arm.calibration.yaml").is_file());

    // 4. The calibration named in robot.yaml, as the step says: its
    // commented line uncommented.
    let text = std::fs::read_to_string(&robot).expect("robot.yaml");
    let named = text.replace("\n# calibration: my-arm", "\ncalibration: my-arm");
    assert_ne!(named, text, "robot.yaml has the line to uncomment");
    std::fs::write(&robot, named).expect("edits");

    // 5. doctor again: nothing wrong (its fixes, if any, run as printed).
    let (code, commands, report) = doctor(&arm, &port);
    for fix in &commands {
        run_as_printed(&arm, fix);
    }
    assert_eq!(code, 0, "doctor after calibrating: {report}");

    // 6. teach, before the hand's poses at 80 s.
    let at = sim.started.elapsed().as_secs_f64();
    assert!(
        at < 80.0,
        "calibrated and checked by {at:.0} s: too late to teach"
    );
    let taught = arm.join("taught.yaml");
    let out = run_in(
        &arm,
        &[
            "teach",
            "--robot",
            "robot.yaml",
            "--port",
            &port,
            "--yes",
            "--duration",
            "25",
            "-o",
            "taught.yaml",
        ],
    );
    assert!(out.status.success(), "teach: {}", stderr(&out));
    let motion: serde_yaml::Value =
        serde_yaml::from_str(&std::fs::read_to_string(&taught).expect("taught.yaml"))
            .expect("YAML");
    let names = common::SO101_JOINTS;
    let poses: Vec<Vec<f64>> = motion["keyframes"]
        .as_sequence()
        .expect("keyframes")
        .iter()
        .map(|k| {
            names
                .iter()
                .map(|n| k["pose"][*n].as_f64().expect("every joint"))
                .collect()
        })
        .collect();
    // The start (the calibration pose), the two poses and the rest.
    let want = [
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [30.0, -40.0, 50.0, 20.0, 45.0, 40.0],
        [-45.0, 20.0, -30.0, -20.0, -60.0, 70.0],
        [0.0, -90.0, 90.0, 45.0, 0.0, 10.0],
    ];
    assert_eq!(poses.len(), want.len(), "{poses:?}");
    for (got, want) in poses.iter().zip(&want) {
        for (g, w) in got.iter().zip(want) {
            assert!(
                (g - w).abs() <= 1.0,
                "taught {got:?}, the hand held {want:?}"
            );
        }
    }

    // 7. play, once the hand has let go. A host that takes the CPU from the
    // simulator's process for several reads in a row stops a run with a
    // fault (as it should on real servos): such a run is played again, up
    // to three times.
    sim.wait_until(95.0);
    let mut played_from = 0.0;
    let mut failed = None;
    for _ in 0..3 {
        played_from = sim.started.elapsed().as_secs_f64();
        let out = run_in(&arm, &["play", "taught.yaml", "--port", &port]);
        if out.status.success() {
            failed = None;
            break;
        }
        assert!(
            stdout(&out).contains("FAULT"),
            "play failed before running: {}{}",
            stdout(&out),
            stderr(&out)
        );
        failed = Some(stdout(&out));
    }
    assert!(failed.is_none(), "play stopped three times: {failed:?}");
    sim.stop();

    // The arm passed through every taught pose (all joints at once).
    let (header, rows) = read_truth(&truth);
    assert_eq!(header[1..], names.map(String::from)[..]);
    let played: Vec<&Vec<f64>> = rows.iter().filter(|r| r[0] >= played_from).collect();
    assert!(
        played.len() > 50,
        "truth rows while playing: {}",
        played.len()
    );
    for pose in &poses {
        let closest = played
            .iter()
            .map(|r| {
                r[1..]
                    .iter()
                    .zip(pose)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max)
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            closest <= 1.0,
            "the arm passed {pose:?} within {closest:.2} deg"
        );
    }
}
