//! `servobus follow` with both arms simulated: the built-in hand moves the
//! leader, the follower follows it, the report gives the latency and the
//! error, and the followed take is saved as a recording `play` plays.

use crate::common;

/// `follow --robot so101 --leader PORT --seconds SECONDS --json`, then
/// `more`: the SO-101 following a leader arm on `port`.
fn follow_leader<'a>(port: &'a str, seconds: &'a str, more: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "follow",
        "--robot",
        "so101",
        "--leader",
        port,
        "--seconds",
        seconds,
        "--json",
    ];
    args.extend_from_slice(more);
    args
}

#[test]
fn follow_runs_both_arms_simulated_reports_latency_and_error_and_saves_a_take() {
    let take = common::scratch("follow").join("take.csv");
    let args = common::follow_hand("6", &["--json", "--record", common::arg(&take)]);
    let out = common::servobus(&args);
    let (stdout, _) = common::exited(&out, 0);
    let report: serde_json::Value = serde_json::from_str(&stdout).expect("one JSON object");
    assert_eq!(report["finish"], "stopped", "{report}");
    let follow = &report["follow"];
    // From a leader reading to the follower's goals on the wire: the 99th
    // percentile under 3 control periods (5 ms at the SO-101's 200 Hz), as
    // issue 24 asks. Measured with a debug build: p99 3.0-5.5 ms, also
    // with two CPU hogs on 2 cores (p50 2.9-4.7 ms). One latency of each
    // run used to be 44-47 ms: the first target, taken before the
    // follower's loop had started (its 50 ms start gap), which the figures
    // now leave out (max 3.1-5.7 ms since). The maximum is reported, not
    // bounded: a loaded machine may hold up one cycle. This runs on the
    // wall clock, so the bound here is 10 periods, a check that the
    // figure is a latency at all (the gate once saw p99 above 15 ms with
    // other tests running); the 3-period figure is read from this report
    // on a quiet host, and the latency of the path itself is held in
    // virtual time (crates/robot/tests/robot/live_follow.rs).
    let period = common::num(follow, "period_ms");
    assert!((period - 5.0).abs() < 1e-9, "{follow}");
    let p50 = common::num(&follow["latency_ms"], "p50");
    let p99 = common::num(&follow["latency_ms"], "p99");
    assert!(p50 <= p99 && p99 < 10.0 * period, "{follow}");
    let joints = follow["joints"].as_array().expect("joints");
    assert_eq!(joints.len(), 6);
    // Issue 24 asks for 2 deg. Each follower reading is compared with the
    // leader's pose at that reading's own time (interpolated between the
    // leader's 50 Hz readings), so a thread that reads late no longer
    // shows as error; a follower cycle delayed on a loaded machine still
    // moves the follower late, and that is real error. Measured with a
    // release build while another engineer built the workspace: worst
    // joint 0.6-1.7 deg worst, 0.2-0.4 deg RMS (the newest leader reading
    // against the newest follower reading, as before, gave up to 5.7 deg
    // and 1.2 deg RMS under load). A follower brought to rest before every
    // target by its lead ran 5-14 deg worst and 1.9-5.4 deg RMS. The bounds
    // are twice the figure worst and half of it RMS; the close
    // following itself is held in virtual time
    // (crates/robot/tests/robot/live_follow.rs).
    // Since the follower no longer extrapolates past the newest reading
    // (issue 35: it never goes beyond what it was told), it trails the
    // leader by one 50 Hz reading interval by design: the base's fastest
    // swing of the hand, about 150 deg/s, is 3 deg in 20 ms, and a cycle
    // late on a loaded machine adds its own. Measured with a debug build
    // while other tests ran: 5.7-7.7 deg worst, 1.3-2.0 deg RMS (the lift
    // or the base); in the gate, with three CLI tests at once on 2 cores,
    // once 18.4 deg worst and 6.4 deg RMS (the lift): readings late under
    // load stop the follower at the newest one. Bounds: 30 deg worst, 10
    // deg RMS, a check that the follower follows at all; how closely it
    // follows is held in virtual time (live_follow.rs: 2 deg of the leader,
    // one interval and the servo's lag before).
    for j in joints {
        assert!(common::num(j, "max_error") < 30.0, "{j}");
        assert!(common::num(j, "rms_error") < 10.0, "{j}");
    }
    // The take: a header and one row per follower cycle, in degrees.
    let text = std::fs::read_to_string(&take).expect("the take is written");
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("time_s,shoulder_pan,shoulder_lift,elbow_flex,wrist_flex,wrist_roll,gripper")
    );
    assert!(lines.count() > 1000, "six seconds at 200 Hz");
    // `play` plays it (in virtual time).
    let play = common::servobus(&[
        "play",
        common::arg(&take),
        "--robot",
        "so101",
        "--fast",
        "--json",
    ]);
    common::exited(&play, 0);
}

/// The follower's gripper blocked at 20 deg on its closing side (an object
/// in its jaws, or a jaw mounted badly), the robot file's mounting
/// otherwise: the gripper's design zero is tick 2048 plus its offset of
/// -20 deg.
const BLOCKED_GRIPPER: &str =
    "gripper: {zero_tick: 1820.4444444444443, direction: 1, stops: [20, 102]}\n";

/// A hand that opens the leader's gripper, closes it to 0 (20 deg past the
/// follower's stop), holds it closed 2 s, then opens it again.
const CLOSING_HAND: &str = "keyframes:
  - at: 0
    pose: {shoulder_pan: 0, shoulder_lift: -90, elbow_flex: 90, wrist_flex: 45, wrist_roll: 0, gripper: 50}
  - at: 1.5
    pose: {shoulder_pan: 0, shoulder_lift: -90, elbow_flex: 90, wrist_flex: 45, wrist_roll: 0, gripper: 50}
  - at: 2.5
    pose: {shoulder_pan: 0, shoulder_lift: -90, elbow_flex: 90, wrist_flex: 45, wrist_roll: 0, gripper: 0}
  - at: 4.5
    pose: {shoulder_pan: 0, shoulder_lift: -90, elbow_flex: 90, wrist_flex: 45, wrist_roll: 0, gripper: 0}
  - at: 5.5
    pose: {shoulder_pan: 0, shoulder_lift: -90, elbow_flex: 90, wrist_flex: 45, wrist_roll: 0, gripper: 60}
  - at: 7
    pose: {shoulder_pan: 0, shoulder_lift: -90, elbow_flex: 90, wrist_flex: 45, wrist_roll: 0, gripper: 60}
";

#[test]
fn a_follower_gripper_closed_on_its_stop_is_held_and_reported_and_the_session_goes_on() {
    let dir = common::scratch("follow-stall");
    let mounting = common::write_file(&dir, "mounting.yaml", BLOCKED_GRIPPER);
    let hand = common::write_file(&dir, "hand.yaml", CLOSING_HAND);
    let follower = common::Sim::start_with(&dir, &["--mounting", common::arg(&mounting)]);
    let out = common::servobus(&[
        "follow",
        "--robot",
        "so101",
        "--port",
        follower.port(),
        "--leader-hand",
        common::arg(&hand),
        "--seconds",
        "7",
        "--json",
    ]);
    // Before issue 35 the stall ended the session (Hold, exit 1).
    let (stdout, stderr) = common::exited(&out, 0);
    let report: serde_json::Value = serde_json::from_str(&stdout).expect("one JSON object");
    assert_eq!(report["finish"], "stopped", "{report}");
    assert!(report["fault"].is_null(), "{report}");
    // The stall is reported: a warning line, the event, the joint's count.
    assert!(
        stderr.contains("warning: gripper (ID 6) stalled at"),
        "{stderr}"
    );
    let stalls = report["follow"]["stalls"].as_array().expect("stalls");
    let held = stalls
        .iter()
        .find(|s| s["held"] == true)
        .unwrap_or_else(|| panic!("a held stall in {stalls:?}"));
    assert_eq!(held["joint"], "gripper", "{held}");
    // Held on the stop, once the leader's gripper has closed past it.
    let at = common::num(held, "position");
    assert!((at - 20.0).abs() < 1.5, "{held}");
    assert!((2.0..4.5).contains(&common::num(held, "time_s")), "{held}");
    // Let go when the leader opens the gripper again.
    assert!(
        stalls.iter().any(|s| s["held"] == false),
        "let go again: {stalls:?}"
    );
    let gripper = &report["joints"][5];
    assert_eq!(gripper["name"], "gripper");
    assert!(common::num(gripper, "stalls") >= 1.0, "{gripper}");
    assert!(common::num(gripper, "stalled_s") > 1.0, "{gripper}");
    follower.stop();
}

#[test]
fn follow_with_its_leader_killed_mid_run_writes_the_log_the_recording_and_the_report() {
    let dir = common::scratch("follow-leader-lost");
    let log = dir.join("fl.csv");
    let take = dir.join("fr.csv");
    let leader = common::Sim::start(&dir);
    let follow = common::Running::start(&follow_leader(
        leader.port(),
        "30",
        &["--log", common::arg(&log), "--record", common::arg(&take)],
    ));
    // 6 s into the leader's simulator (a few seconds of following, after
    // the follower's start-up, which takes more than 3 s on a loaded
    // machine), it is killed: the leader's port just goes.
    leader.wait_until(6.0);
    drop(leader);
    let (status, stdout, stderr) = follow.finish();
    assert_eq!(status.code(), Some(1), "stdout {stdout} stderr {stderr}");
    assert!(stderr.contains("error: the leader was lost at"), "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&stdout).expect("the report, as JSON");
    let lost = report["follow"]["leader_lost"].as_str().expect("why");
    assert!(lost.starts_with("the leader was lost at"), "{lost}");
    assert_eq!(report["finish"], "stopped", "{report}");
    let cycles = common::num(&report, "cycles");
    assert!(cycles > 200.0, "a few seconds at 200 Hz: {cycles}");
    // The log: a header and rows of every joint up to the end.
    let log = std::fs::read_to_string(&log).expect("the log is written");
    assert!(log.lines().count() > 1000, "{} lines", log.lines().count());
    // The recording: a header and one row per follower cycle, in degrees.
    let text = std::fs::read_to_string(&take).expect("the recording is written");
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("time_s,shoulder_pan,shoulder_lift,elbow_flex,wrist_flex,wrist_roll,gripper")
    );
    assert!(lines.count() as f64 >= cycles * 0.9, "{cycles} cycles");
}

#[test]
fn a_leader_that_drops_replies_is_followed_and_the_skipped_readings_are_counted() {
    // A loaded machine or a noisy cable: one leader reply in ten is lost.
    // A lost reading is skipped (the follower keeps to that joint's last
    // target), counted, and does not end the session.
    let dir = common::scratch("follow-leader-drops");
    let leader = common::Sim::start_with(&dir, &["--faults", "drop=0.1,seed=3"]);
    let follow = common::Running::start(&follow_leader(leader.port(), "3", &[]));
    let (status, stdout, stderr) = follow.finish();
    assert_eq!(status.code(), Some(0), "stdout {stdout} stderr {stderr}");
    assert!(stderr.contains("leader readings were skipped"), "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&stdout).expect("the report, as JSON");
    assert_eq!(report["finish"], "stopped", "{report}");
    assert!(report["follow"]["leader_lost"].is_null(), "{report}");
}

#[test]
fn off_a_terminal_the_live_line_is_whole_lines_without_carriage_returns() {
    // Stderr to a pipe (a log): the live line comes every 5 s, each on a
    // line of its own, not rewritten in place with `\r`.
    let out = common::servobus(&common::follow_hand("6", &[]));
    let (_, stderr) = common::exited(&out, 0);
    assert!(!stderr.contains('\r'), "{stderr:?}");
    let live: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains(" s  leader ") && l.contains(" Hz  follower "))
        .collect();
    assert_eq!(live.len(), 1, "one live line in 6 s: {stderr}");
    assert!(live[0].contains("error max"), "{stderr}");
}
