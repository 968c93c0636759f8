//! The whole flow on the command line, on a pty, in wall-clock time:
//! `servobus sim` with a badly fitted body, a scripted hand and the truth;
//! `servobus calibrate --port … --yes` while the hand poses and sweeps the
//! joints; then `servobus play … --port …`, and the truth compared with the
//! motion's keyframes. A hexapod with a random unit calibrates as well.

use crate::common;

use std::path::Path;
use std::sync::Mutex;

use common::{
    arg, edited, read_truth, repo, says, scratch, servobus, servobus_ok, stdout, write_file, Sim,
};
use servobus_runtime::config::{load_motion, load_robot, Robot, RobotOptions};

/// The two flows run one after the other: each is a simulator and a client
/// in wall-clock time, and two at once on a small machine starve both.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// A hand file: from `start`, to the calibration pose (all 0) by 4 s, held;
/// then the joint groups in turn to their upper end, lower end and back
/// (`ends`, degrees, per joint); held until it lets go. Returns the file's
/// text and the time it lets go.
fn hand(robot: &Robot, start: &[f64], ends: &[(f64, f64)], groups: &[Vec<usize>]) -> (String, f64) {
    let n = robot.joint_count();
    let zero = vec![0.0; n];
    let mut keys: Vec<(f64, Vec<f64>)> = vec![
        (0.0, start.to_vec()),
        (3.0, start.to_vec()),
        (4.0, zero.clone()),
        (7.0, zero.clone()),
    ];
    let mut t = 7.0;
    for group in groups {
        let pose = |upper: Option<bool>| -> Vec<f64> {
            (0..n)
                .map(|j| match (group.contains(&j), upper) {
                    (true, Some(true)) => ends[j].1,
                    (true, Some(false)) => ends[j].0,
                    _ => 0.0,
                })
                .collect()
        };
        for (dt, p) in [
            (0.7, pose(Some(true))),
            (0.2, pose(Some(true))),
            (0.9, pose(Some(false))),
            (0.2, pose(Some(false))),
            (0.5, pose(None)),
        ] {
            t += dt;
            keys.push((t, p));
        }
    }
    let end = t + 3.5;
    keys.push((end, zero));
    let names: Vec<String> = robot.joints().map(|j| j.name.clone()).collect();
    let mut text = String::from("keyframes:\n");
    for (at, pose) in keys {
        let pose: Vec<String> = names
            .iter()
            .zip(pose)
            .map(|(name, a)| format!("{name}: {a}"))
            .collect();
        text.push_str(&format!(
            "  - {{at: {at}, pose: {{{}}}}}\n",
            pose.join(", ")
        ));
    }
    (text, end)
}

fn calibrate(robot: &Path, sim: &Sim, cal: &Path) -> String {
    let robot = arg(robot);
    stdout(&servobus_ok(&[
        "calibrate",
        "--robot",
        robot,
        "--port",
        sim.port(),
        "--yes",
        "-o",
        arg(cal),
    ]))
}

#[test]
#[ignore = "a person's hand in real time, 20-30 s: `cargo test --test cli -- --ignored` (the gate runs it)"]
fn an_arm_is_calibrated_on_the_command_line_then_plays_where_it_is_told() {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = scratch("calib-flow-arm");
    // The SO-101 with more latency in its bus settings, as a user puts
    // their adapter's: the simulator answers from a process that may wait
    // for the CPU on a loaded host, so replies are given 8 ms, at 50 Hz.
    let edits = [
        ("latency_us: auto ", "latency_us: 8000 "),
        ("rate: 200 ", "rate: 50 "),
    ];
    let robot_file = write_file(
        &dir,
        "so101.yaml",
        &edited("configs/robots/so101.yaml", &edits),
    );
    let robot = load_robot(&robot_file, &RobotOptions::default()).expect("so101");
    // The shipped badly fitted arm: the lift's range crosses the seam, the
    // elbow and wrist are reversed. The hand sweeps to the stops (the roll
    // has none: a little past its limits).
    let ends = [
        (-115.0, 115.0),
        (-105.0, 105.0),
        (-100.0, 100.0),
        (-100.0, 100.0),
        (-163.0, 163.0),
        (-2.0, 102.0),
    ];
    let start = [0.0, -90.0, 90.0, 45.0, 0.0, 10.0];
    let groups: Vec<Vec<usize>> = (0..6).map(|j| vec![j]).collect();
    let (text, lets_go) = hand(&robot, &start, &ends, &groups);
    let mounting = repo("configs/sim/so101-mounting.yaml");
    let body = ["--mounting", arg(&mounting)];
    let (sim, truth_file) = Sim::start_hand(&dir, &robot_file, 6, &text, &body);
    let cal = dir.join("arm.calibration.yaml");
    let said = calibrate(&robot_file, &sim, &cal);
    says(
        &said,
        &[
            "1. Torque is off",
            "2. Hold the robot",
            "3. Move every joint",
            "4. Done",
        ],
    );
    assert!(
        said.contains("shoulder_lift") && said.contains("across the seam"),
        "{said}"
    );
    // The person steps back; then the arm plays.
    sim.wait_until(lets_go + 0.5);
    // arm-wave at the rate this bus allows.
    let wave = edited(
        "configs/motions/arm-wave.yaml",
        &[("rate: 200 ", "rate: 50 ")],
    );
    let motion = write_file(&dir, "arm-wave.yaml", &wave);
    // A host that takes the CPU from the simulator's process for a few
    // reads in a row stops a run with a fault (as it should on real
    // servos): such a run is played again, up to three times.
    let mut played_from = 0.0;
    let mut last = None;
    for _ in 0..3 {
        played_from = sim.started.elapsed().as_secs_f64();
        let out = servobus(&[
            "play",
            arg(&motion),
            "--robot",
            arg(&robot_file),
            "--port",
            sim.port(),
            "--calibration",
            arg(&cal),
        ]);
        let text = stdout(&out);
        if out.status.success() {
            last = None;
            break;
        }
        let err = common::stderr(&out);
        assert!(
            text.contains("FAULT"),
            "play failed before running: {text}{err}"
        );
        last = Some(text);
    }
    assert!(last.is_none(), "play stopped three times: {last:?}");
    sim.stop();

    let (header, rows) = read_truth(&truth_file);
    let names: Vec<String> = robot.joints().map(|j| j.name.clone()).collect();
    assert_eq!(header[1..], names[..]);
    let (m, _) = load_motion(&motion, Some(&robot_file)).expect("motion");
    let played: Vec<&Vec<f64>> = rows.iter().filter(|r| r[0] >= played_from).collect();
    assert!(
        played.len() > 100,
        "truth rows while playing: {}",
        played.len()
    );
    // Every keyframe: the body passed through it (all joints at once).
    for (k, kf) in m.keyframes.iter().enumerate() {
        let closest = played
            .iter()
            .map(|r| {
                r[1..]
                    .iter()
                    .zip(&kf.positions)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max)
            })
            .fold(f64::INFINITY, f64::min);
        println!("keyframe {k}: closest {closest:.2} deg");
        assert!(
            closest < 1.0,
            "keyframe {k}: the body came within {closest:.2} deg only"
        );
    }
}

#[test]
#[ignore = "a person's hand in real time, 20-30 s: `cargo test --test cli -- --ignored` (the gate runs it)"]
fn a_hexapod_with_a_random_unit_is_calibrated_on_the_command_line() {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = scratch("calib-flow-hexapod");
    let robot_file = repo("configs/robots/hexapod.yaml");
    let robot = load_robot(&robot_file, &RobotOptions::default()).expect("hexapod");
    // The random unit's stops are 5 deg past the limits; the hand goes 4.
    let ends: Vec<(f64, f64)> = robot.joints().map(|j| (j.min - 4.0, j.max + 4.0)).collect();
    let start: Vec<f64> = robot.joints().map(|j| j.rest()).collect();
    // Coxas together, then femurs, then tibias.
    let groups: Vec<Vec<usize>> = (0..3)
        .map(|k| (0..6).map(|leg| leg * 3 + k).collect())
        .collect();
    let (text, _) = hand(&robot, &start, &ends, &groups);
    let (sim, _) = Sim::start_hand(&dir, &robot_file, 18, &text, &["--unit", "5"]);
    let cal = dir.join("hexapod.calibration.yaml");
    let said = calibrate(&robot_file, &sim, &cal);
    assert!(said.contains("across the seam"), "{said}");
    sim.stop();
    // Each joint's measured range is where the hand took it.
    let robot = servobus_runtime::config::load_robot(
        &robot_file,
        &RobotOptions::default().calibration(Some(&cal)),
    )
    .expect("the calibration applies");
    for (j, &(lo, hi)) in robot.joints().zip(&ends) {
        let c = j.calibration.as_ref().expect("calibrated");
        let (a, b) = c.range_deg(j.model);
        assert!(
            (a - lo).abs() < 1.0 && (b - hi).abs() < 1.0,
            "{}: measured {a:.1}..{b:.1}, hand {lo}..{hi}",
            j.name
        );
    }
}
