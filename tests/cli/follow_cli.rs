//! `servobus follow` with both arms simulated: the built-in hand moves the
//! leader, the follower follows it, the report gives the latency and the
//! error, and the followed take is saved as a recording `play` plays.

use crate::common;

#[test]
fn follow_runs_both_arms_simulated_reports_latency_and_error_and_saves_a_take() {
    let take = common::scratch("follow").join("take.csv");
    let args = [
        "follow",
        "--robot",
        "so101",
        "--leader-hand",
        "so101-hand",
        "--seconds",
        "6",
        "--json",
        "--record",
        common::arg(&take),
    ];
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
    // bounded: a loaded machine may hold up one cycle.
    let period = common::num(follow, "period_ms");
    assert!((period - 5.0).abs() < 1e-9, "{follow}");
    let p50 = common::num(&follow["latency_ms"], "p50");
    let p99 = common::num(&follow["latency_ms"], "p99");
    assert!(p50 <= p99 && p99 < 3.0 * period, "{follow}");
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
    // (crates/runtime/tests/runtime/live_follow.rs).
    for j in joints {
        assert!(common::num(j, "max_error") < 4.0, "{j}");
        assert!(common::num(j, "rms_error") < 1.0, "{j}");
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
