//! `servobus sim` with a body on a pty: a mounting, a hand and the truth
//! file, while a client reads positions.

use crate::common;

use std::time::{Duration, Instant};

use common::{arg, read_truth, repo, scratch, servobus_fails, write_file, Sim};

/// Ticks per degree of an STS3215.
const TPD: f64 = 4096.0 / 360.0;

/// The tick a servo mounted with its zero at `zero` and direction `dir`
/// reads at `angle` degrees.
fn raw(zero: f64, dir: f64, angle: f64) -> i64 {
    ((zero + dir * angle * TPD).round() as i64).rem_euclid(4096)
}

#[test]
fn sim_with_mounting_hand_and_truth_on_a_pty() {
    let dir = scratch("sim-body");
    // Lift from -90 to +40 deg between 1 and 2 s: across its servo's seam
    // in the shipped mounting (zero tick 3900). The hand then lets go.
    let hand = "keyframes:\n  - {at: 0, pose: {shoulder_lift: -90}}\n  - {at: 1, pose: {shoulder_lift: -90}}\n  - {at: 2, pose: {shoulder_lift: 40}}\n";
    let mounting = repo("configs/sim/so101-mounting.yaml");
    let robot = repo("configs/robots/so101.yaml");
    let started = Instant::now();
    let (sim, truth) = Sim::start_hand(&dir, &robot, 6, hand, &["--mounting", arg(&mounting)]);
    std::thread::sleep(Duration::from_millis(2500).saturating_sub(started.elapsed()));
    // The hand has let go at +40 deg: tick 3900 + 40 * 4096 / 360 = 4355 -> 259.
    let lift = sim.read("2", "present_position");
    assert!(
        (lift - raw(3900.0, 1.0, 40.0)).abs() <= 1,
        "lift reads {lift}"
    );
    // The elbow (reversed, zero 2500) rests at its home, 90 deg.
    let elbow = sim.read("3", "present_position");
    assert!(
        (elbow - raw(2500.0, -1.0, 90.0)).abs() <= 1,
        "elbow reads {elbow}"
    );
    std::thread::sleep(Duration::from_millis(3500).saturating_sub(started.elapsed()));
    let ran = started.elapsed().as_secs_f64();
    sim.stop();

    let (header, rows) = read_truth(&truth);
    assert_eq!(
        header.join(","),
        "time_s,shoulder_pan,shoulder_lift,elbow_flex,wrist_flex,wrist_roll,gripper"
    );
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
    let bad = write_file(
        &dir,
        "m.yaml",
        "shoulder_pan: {zero_tick: 100}\nelbow_flex: {zero_tick: 9, direction: 0}\n",
    );
    let robot = repo("configs/robots/so101.yaml");
    let err = servobus_fails(&["sim", "--robot", arg(&robot), "--mounting", arg(&bad)]);
    assert!(
        err.contains("m.yaml:2:") && err.contains("elbow_flex.direction"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}
