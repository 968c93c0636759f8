//! `servobus sim` with a body on a pty: a mounting, a hand and the truth
//! file, while a client reads positions.

mod common;

use std::process::Command;
use std::time::{Duration, Instant};

use common::{repo, scratch, Sim, BIN};

/// Ticks per degree of an STS3215.
const TPD: f64 = 4096.0 / 360.0;

/// Present position of servo `id` as `servobus read` gets it.
fn read_position(sim: &Sim, id: &str) -> i64 {
    let out = Command::new(BIN)
        .args(["read", "--id", id, "present_position", "--json"])
        .args(["--port", sim.port(), "--latency-us", "10000"])
        .output()
        .expect("run servobus read");
    assert!(
        out.status.success(),
        "read failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("read --json");
    v["value"].as_i64().expect("value")
}

fn raw(zero: f64, dir: f64, angle: f64) -> i64 {
    ((zero + dir * angle * TPD).round() as i64).rem_euclid(4096)
}

#[test]
fn sim_with_mounting_hand_and_truth_on_a_pty() {
    let dir = scratch("sim-body");
    let hand = dir.join("hand.yaml");
    // Lift from -90 to +40 deg between 1 and 2 s: across its servo's seam
    // in the shipped mounting (zero tick 3900). The hand then lets go.
    std::fs::write(
        &hand,
        "keyframes:\n  - {at: 0, pose: {shoulder_lift: -90}}\n  - {at: 1, pose: {shoulder_lift: -90}}\n  - {at: 2, pose: {shoulder_lift: 40}}\n",
    )
    .expect("writes the hand");
    let truth = dir.join("truth.csv");
    let mounting = repo("configs/sim/so101-mounting.yaml");
    let started = Instant::now();
    let sim = Sim::start_with(
        &dir,
        &[
            "--mounting",
            mounting.to_str().expect("utf-8"),
            "--hand",
            hand.to_str().expect("utf-8"),
            "--truth",
            truth.to_str().expect("utf-8"),
        ],
    );
    std::thread::sleep(Duration::from_millis(2500).saturating_sub(started.elapsed()));
    // The hand has let go at +40 deg: tick 3900 + 40 * 4096 / 360 = 4355 -> 259.
    let lift = read_position(&sim, "2");
    assert!(
        (lift - raw(3900.0, 1.0, 40.0)).abs() <= 1,
        "lift reads {lift}"
    );
    // The elbow (reversed, zero 2500) rests at its home, 90 deg.
    let elbow = read_position(&sim, "3");
    assert!(
        (elbow - raw(2500.0, -1.0, 90.0)).abs() <= 1,
        "elbow reads {elbow}"
    );
    std::thread::sleep(Duration::from_millis(3500).saturating_sub(started.elapsed()));
    let ran = started.elapsed().as_secs_f64();
    sim.stop();

    let text = std::fs::read_to_string(&truth).expect("the truth file");
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("time_s,shoulder_pan,shoulder_lift,elbow_flex,wrist_flex,wrist_roll,gripper")
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().expect("a number")).collect())
        .collect();
    let last = rows.last().expect("rows")[0];
    assert!(
        last > 3.0 && last < ran + 0.1,
        "ran {ran} s, truth to {last} s"
    );
    let per_second = (rows.len() - 1) as f64 / last;
    assert!(per_second >= 50.0, "{per_second} rows a second");
    let at = |t: f64| {
        rows.iter()
            .find(|r| (r[0] - t).abs() < 0.006)
            .unwrap_or_else(|| panic!("a row at {t} s"))
    };
    assert!((at(0.5)[2] + 90.0).abs() < 0.01);
    assert!((at(1.5)[2] + 25.0).abs() < 0.01, "halfway: {}", at(1.5)[2]);
    assert!((at(3.0)[2] - 40.0).abs() < 0.01);
    assert!((at(3.0)[3] - 90.0).abs() < 0.01);
}

#[test]
fn sim_refuses_a_bad_mounting_with_file_line_and_field() {
    let dir = scratch("sim-body-bad");
    let bad = dir.join("m.yaml");
    std::fs::write(
        &bad,
        "shoulder_pan: {zero_tick: 100}\nelbow_flex: {zero_tick: 9, direction: 0}\n",
    )
    .expect("writes");
    let out = Command::new(BIN)
        .args(["sim", "--robot"])
        .arg(repo("configs/robots/so101.yaml"))
        .arg("--mounting")
        .arg(&bad)
        .output()
        .expect("runs");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("m.yaml:2:") && err.contains("elbow_flex.direction"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}
