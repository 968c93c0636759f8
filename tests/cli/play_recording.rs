//! `servobus play` of recorded paths (a `time_s,<joint>...` CSV and the
//! CSV `play --log` writes): played within every limit, checked here by
//! differencing what was sent (the log's commanded positions), and a
//! smooth recording reproduced closely. Also: outputs are checked before
//! anything moves.

use crate::common;

use std::path::{Path, PathBuf};

use common::{num, scratch, servobus, servobus_json};

/// so101 with a fixed lead, so that what is sent is the path itself.
fn robot(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(common::repo("configs/robots/so101.yaml")).expect("so101");
    let p = dir.join("so101.yaml");
    std::fs::write(&p, format!("lead_ms: 10\n{text}")).expect("robot");
    p
}

/// `servobus play RECORDING --robot ROBOT --fast --json EXTRA...`, which
/// must succeed: its JSON report.
fn play_json(recording: &Path, robot: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec![
        "play",
        recording.to_str().expect("utf-8"),
        "--robot",
        robot.to_str().expect("utf-8"),
        "--fast",
        "--json",
    ];
    args.extend_from_slice(extra);
    servobus_json(&args)
}

/// Limits of so101's shoulder_pan and elbow_flex (deg, deg/s, ...).
const LIMITS: [(f64, f64, f64); 2] = [(180.0, 900.0, 9000.0), (180.0, 900.0, 9000.0)];

fn write_recording(path: &Path, noisy: bool) {
    let mut seed: u64 = 0x2545_f491_4f6c_dd1d;
    let mut noise = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut text = String::from("time_s,shoulder_pan,elbow_flex\n");
    for i in 0..=600 {
        let t = i as f64 * 0.01;
        let (a, b) = if noisy {
            // Steps of 60 deg every 1.5 s and a fast swing, with noise.
            let step = if ((t / 1.5) as u32).is_multiple_of(2) {
                -30.0
            } else {
                30.0
            };
            (step + 2.0 * noise(), 40.0 * (4.0 * t).sin() + noise())
        } else {
            // Out and back twice from rest, well within the limits.
            let w = std::f64::consts::PI * 2.0 / 3.0;
            (20.0 * (1.0 - (w * t).cos()), 25.0 - 25.0 * (w * t).cos())
        };
        text += &format!("{t:.3},{a:.4},{b:.4}\n");
    }
    std::fs::write(path, text).expect("recording");
}

/// A scratch folder `name` holding the robot and a recording
/// (`take.csv`, noisy or smooth): the folder, the robot and the recording.
fn take(name: &str, noisy: bool) -> (PathBuf, PathBuf, PathBuf) {
    let dir = scratch(name);
    let robot = robot(&dir);
    let rec = dir.join("take.csv");
    write_recording(&rec, noisy);
    (dir, robot, rec)
}

/// Commanded positions per joint from a `play --log` file.
fn commanded(log: &Path, joint: &str) -> Vec<(f64, f64)> {
    let text = std::fs::read_to_string(log).expect("log");
    text.lines()
        .skip(1)
        .filter_map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[3] == joint).then(|| (f[0].parse().expect("t"), f[4].parse().expect("cmd")))
        })
        .collect()
}

/// Velocity, acceleration and jerk by differences of what was sent (the
/// jerk over 4 cycles, so the log's rounding to 1e-4 deg stays small).
fn check_limits(series: &[(f64, f64)], (vm, am, jm): (f64, f64, f64)) {
    let dt = series[1].0 - series[0].0;
    let p: Vec<f64> = series.iter().map(|s| s.1).collect();
    let q = 1e-4; // the log's rounding
    for i in 0..p.len() - 1 {
        assert!(
            (p[i + 1] - p[i]).abs() / dt <= vm * 1.001 + q / dt,
            "velocity at {i}"
        );
    }
    for i in 1..p.len() - 1 {
        let a = (p[i + 1] - 2.0 * p[i] + p[i - 1]) / (dt * dt);
        assert!(
            a.abs() <= am * 1.001 + 4.0 * q / (dt * dt),
            "acceleration at {i}: {a}"
        );
    }
    let h = 4;
    let hd = h as f64 * dt;
    for i in 0..p.len().saturating_sub(3 * h) {
        let j = (p[i + 3 * h] - 3.0 * p[i + 2 * h] + 3.0 * p[i + h] - p[i]) / (hd * hd * hd);
        assert!(
            j.abs() <= jm * 1.001 + 8.0 * q / (hd * hd * hd),
            "jerk at {i}: {j}"
        );
    }
}

#[test]
fn a_noisy_recording_with_steps_is_played_within_every_limit() {
    let (dir, robot, rec) = take("play_recording_noisy", true);
    let log = dir.join("log.csv");
    let v = play_json(&rec, &robot, &["--log", log.to_str().expect("utf-8")]);
    assert_eq!(v["finish"], "completed", "{v}");
    for (name, lim) in ["shoulder_pan", "elbow_flex"].into_iter().zip(LIMITS) {
        let sent = commanded(&log, name);
        assert!(sent.len() > 1000, "{name}: {} rows", sent.len());
        check_limits(&sent, lim);
    }
    let r = &v["recording"];
    assert_eq!(r["samples"], 601, "{r}");
    // The 60 deg steps cannot be followed instantly: a departure is shown.
    assert!(num(&r["joints"][0], "max_departure") > 10.0, "{r}");

    // The log it wrote plays back too: its planned path, within every
    // limit already, so played as it is.
    let again = play_json(&log, &robot, &[]);
    assert_eq!(again["finish"], "completed", "{again}");
    assert_eq!(again["recording"]["column"], "planned_deg", "{again}");
    assert!(
        num(&again["recording"]["joints"][0], "max_departure") < 0.05,
        "{again}"
    );
}

#[test]
fn a_smooth_recording_is_reproduced_closely() {
    let (_, robot, rec) = take("play_recording_smooth", false);
    let v = play_json(&rec, &robot, &[]);
    for j in v["recording"]["joints"]
        .as_array()
        .expect("joints")
        .iter()
        .take(2)
    {
        assert!(num(j, "max_departure") < 0.5, "{j}");
        assert!(num(j, "rms_departure") < 0.25, "{j}");
    }
}

#[test]
fn outputs_are_checked_before_anything_moves() {
    for (flag, path, says) in [
        ("--plot", "/nonexistent/x.svg", "does not exist"),
        ("--plot", "x.pdf", "SVG (.svg) or PNG (.png)"),
        ("--log", "/nonexistent/x.csv", "does not exist"),
    ] {
        let out = servobus(&[
            "play",
            "configs/motions/arm-wave.yaml",
            "--fast",
            flag,
            path,
        ]);
        assert!(!out.status.success(), "{flag} {path}");
        let stdout = String::from_utf8_lossy(&out.stdout);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(says), "{flag} {path}: {stderr}");
        // Refused before the plan was even printed: nothing ran.
        assert!(!stdout.contains("completed"), "{stdout}");
    }
}
