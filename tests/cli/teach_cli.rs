//! `servobus teach` on a pty: the simulator's hand poses the arm, teach
//! captures the poses without a keyboard, and the file plans as it is.

use crate::common;

use std::process::{Command, Stdio};

use common::{arg, repo, scratch, servobus, servobus_ok, Sim, BIN};

/// A hand's first keyframes: the arm at rest, then at a pose reached in
/// 1 s and held 2 s (until 3.5 s).
const REST_THEN_A_POSE: &str = "keyframes:\n\
     \x20 - {at: 0, pose: {shoulder_pan: 0, elbow_flex: 90}}\n\
     \x20 - {at: 0.5, pose: {shoulder_pan: 0, elbow_flex: 90}}\n\
     \x20 - {at: 1.5, pose: {shoulder_pan: 40, elbow_flex: 30}}\n\
     \x20 - {at: 3.5, pose: {shoulder_pan: 40, elbow_flex: 30}}\n";

/// `servobus teach --yes --duration 6.5` on the SO-101 served by a
/// simulator whose hand plays `hand`; its output and the motion file's path.
fn teach_with_hand(
    dir: &std::path::Path,
    hand: &str,
) -> (std::process::Output, std::path::PathBuf) {
    let robot = repo("configs/robots/so101.yaml");
    let (sim, _) = Sim::start_hand(dir, &robot, 6, hand, &[]);
    let out = dir.join("taught.yaml");
    let run = Command::new(BIN)
        .args(["teach", "--robot"])
        .arg(&robot)
        .args(["--port", sim.port(), "--yes", "--duration", "6.5", "-o"])
        .arg(&out)
        .stdin(Stdio::null())
        .output()
        .expect("runs teach");
    sim.stop();
    (run, out)
}

#[test]
fn teach_captures_the_hands_poses_and_writes_a_playable_file() {
    let dir = scratch("teach-cli");
    // Rest, then two poses, each reached in 1 s and held 2 s.
    let hand = format!(
        "{REST_THEN_A_POSE}\
         \x20 - {{at: 4.5, pose: {{shoulder_pan: -30, elbow_flex: 60}}}}\n\
         \x20 - {{at: 6.5, pose: {{shoulder_pan: -30, elbow_flex: 60}}}}\n"
    );
    let (run, out) = teach_with_hand(&dir, &hand);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{err}");
    assert!(err.contains("torque off"), "{err}");
    let text = std::fs::read_to_string(&out).expect("the motion file");
    assert!(text.starts_with("# Taught by hand"), "{text}");
    let poses: Vec<&str> = text.lines().filter(|l| l.contains("pose:")).collect();
    // The starting pose, then the two poses at the times they were taken.
    assert_eq!(poses.len(), 3, "{text}");
    assert!(
        poses[0].contains("shoulder_pan: 0.0") && poses[0].contains("elbow_flex: 90.0"),
        "{text}"
    );
    assert!(
        poses[1].contains("shoulder_pan: 40.0") || poses[1].contains("shoulder_pan: 39.9"),
        "{text}"
    );
    assert!(
        poses[2].contains("elbow_flex: 60.0") || poses[2].contains("elbow_flex: 59.9"),
        "{text}"
    );
    assert_eq!(text.matches("at: ").count(), 2, "{text}");
    // `play` accepts it as it is: planning it succeeds.
    servobus_ok(&["plan", arg(&out)]);
}

#[test]
fn teach_refuses_an_unknown_joint_to_hold_before_anything_moves() {
    let dir = scratch("teach-cli-bad");
    let sim = Sim::start(&dir);
    let out = servobus(&sim.arm_args(
        &["teach"],
        &[
            "--hold",
            "shoulder,elbow_flex",
            "--yes",
            "-o",
            arg(&dir.join("x.yaml")),
        ],
    ));
    sim.stop();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no joint `shoulder` to hold"), "{err}");
}

#[test]
fn teach_stops_at_a_pose_outside_the_limits_instead_of_clamping_it() {
    let dir = scratch("teach-cli-limits");
    // Rest, a pose, then the elbow taken to 106 deg: past the robot file's
    // 97 deg (the simulator's arm has no stop there).
    let hand = format!(
        "{REST_THEN_A_POSE}\
         \x20 - {{at: 4.5, pose: {{shoulder_pan: 40, elbow_flex: 106}}}}\n\
         \x20 - {{at: 6.5, pose: {{shoulder_pan: 40, elbow_flex: 106}}}}\n"
    );
    let (run, out) = teach_with_hand(&dir, &hand);
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "a problem found: {err}");
    common::says(
        &err,
        &[
            "joint `elbow_flex` was taught at",
            "outside its limits [-97.0, 97.0] deg",
            "comes from the robot file",
            "teach again",
            "widen `min`/`max`",
        ],
    );
    assert!(!err.contains("panicked"), "{err}");
    // What was taught before it is kept, and nothing was clamped to 100.
    let text = std::fs::read_to_string(&out).expect("the keyframes before it");
    let poses: Vec<&str> = text.lines().filter(|l| l.contains("pose:")).collect();
    assert_eq!(poses.len(), 2, "{text}");
    assert!(!text.contains("elbow_flex: 100.00"), "{text}");
}

#[test]
fn a_continuous_take_stopped_with_ctrl_c_mid_move_is_reduced_and_plays() {
    let dir = scratch("teach-cli-interrupted");
    // The pan and elbow move for 12 s without a pause: Ctrl-C comes while
    // they move.
    let hand = "keyframes:\n\
         \x20 - {at: 0, pose: {shoulder_pan: 0, elbow_flex: 90}}\n\
         \x20 - {at: 12, pose: {shoulder_pan: 100, elbow_flex: 30}}\n";
    let robot = repo("configs/robots/so101.yaml");
    let (sim, _) = Sim::start_hand(&dir, &robot, 6, hand, &[]);
    let out = dir.join("take.yaml");
    let mut teach = common::Running::start(&[
        "teach",
        "--robot",
        arg(&robot),
        "--port",
        sim.port(),
        "--continuous",
        "--yes",
        "-o",
        arg(&out),
    ]);
    teach.wait_for(true, "the recording", |l| l.contains("Recording the path"));
    sim.wait_until(5.0);
    teach.interrupt();
    let (status, _, err) = teach.finish();
    sim.stop();
    assert!(status.success(), "{err}");
    let text = std::fs::read_to_string(&out).expect("the take");
    // Reduced (a few keyframes, not one per sample) and checked: the last
    // pose is reached and held a moment after the recording ends.
    let keyframes = text.lines().filter(|l| l.contains("pose:")).count();
    assert!(
        (2..=40).contains(&keyframes),
        "{keyframes} keyframes: {text}"
    );
    assert!(text.contains("ended while the robot moved"), "{text}");
    // `play` accepts it as it is.
    servobus_ok(&["plan", arg(&out)]);
}

/// The `robot:` line of the motion file `text`.
fn robot_line(text: &str) -> &str {
    text.lines()
        .find(|l| l.starts_with("robot:"))
        .unwrap_or_else(|| panic!("no robot: in {text}"))
}

#[test]
fn a_taught_file_names_its_robot_as_given_and_plays_where_it_is_moved() {
    let dir = scratch("teach-cli-moved");
    let arm = dir.join("arm");
    std::fs::create_dir_all(arm.join("motions")).expect("the folder");
    let robot = arm.join("robot.yaml");
    std::fs::copy(repo("configs/robots/so101.yaml"), &robot).expect("a robot file");
    let sim = Sim::start_robot(&dir, std::path::Path::new("so101"), 6, &[]);
    // The arm is still: each take is its starting pose.
    let teach = |robot: &str, out: &std::path::Path| {
        let run = Command::new(BIN)
            .args(["teach", "--robot", robot, "--port", sim.port()])
            .args(["--yes", "--duration", "1.5", "-o"])
            .arg(out)
            .stdin(Stdio::null())
            .output()
            .expect("runs teach");
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "teach --robot {robot}: {err}");
        std::fs::read_to_string(out).expect("the motion file")
    };
    // A built-in robot stays a name; a file is named relative to the motion.
    let by_name = arm.join("by-name.yaml");
    let text = teach("so101", &by_name);
    assert_eq!(robot_line(&text), "robot: so101", "{text}");
    let by_file = arm.join("motions/by-file.yaml");
    let text = teach(arg(&robot), &by_file);
    assert_eq!(robot_line(&text), "robot: ../robot.yaml", "{text}");
    sim.stop();

    // The folder moved elsewhere: both play from there, from another
    // working directory, on the simulator.
    let moved = dir.join("moved");
    std::fs::rename(&arm, &moved).expect("move the folder");
    for file in ["by-name.yaml", "motions/by-file.yaml"] {
        let path = moved.join(file);
        let out = common::servobus_in(&dir, &["play", arg(&path), "--fast", "--json"]);
        let report = common::json(&common::succeeded(out, &["play", file]));
        assert_eq!(report["finish"], "completed", "{file}: {report}");
    }
}
