//! The relay on a virtual-time run of the simulated SO-101
//! ([`crate::node::virtual_node`]).

use std::sync::atomic::Ordering;

use servobus_robot::Finish;

use crate::node::virtual_node::{spread, Node, PAN};

#[test]
fn stop_holds_the_following_and_the_next_target_moves_again() {
    let mut node = Node::new();
    let dt = node.period();
    // Targets ramp the pan at 40 deg/s at 30 Hz; `stop` at 0.75 s, while
    // it moves, and the sender goes quiet (its next target would move the
    // arm again).
    let going = node.run_for(1200, |node, k| {
        let t = k as f64 * dt;
        if k % 7 == 0 && k < 150 {
            node.target(&format!(
                r#"{{"t": {t}, "joints": {{"shoulder_pan": {}}}}}"#,
                40.0 * t
            ));
        }
        if k == 150 {
            node.command("stop");
        }
    });
    assert!(going, "the run goes on after stop");
    let pan = node.joint(PAN, 0);
    let at_stop = pan[150];
    assert!(at_stop > 20.0, "moving when stopped: {at_stop}");
    // Stopped soon after (not carried on to the ramp's 40 deg), held still
    // for the rest of the 6 s.
    let held = pan[400];
    assert!(held < at_stop + 5.0, "{at_stop} -> {held}");
    assert!(spread(&node.commanded[400..]) < 1e-9, "held");
    // Following a stop is a plain pause: `resume` does not restart the
    // stopped motion.
    node.command("resume");
    assert!(node.run_for(200, |_, _| {}));
    assert!(
        spread(&node.commanded[400..]) < 1e-9,
        "resume is not a way out"
    );
    // A new target moves the arm again, and the node goes on serving.
    assert!(node.run_for(400, |node, k| {
        if k % 7 == 0 {
            let t = k as f64 * dt;
            node.target(&format!(
                r#"{{"t": {t}, "joints": {{"shoulder_pan": -20}}}}"#
            ));
        }
    }));
    let last = *node.joint(PAN, 0).last().expect("cycles");
    assert!((last + 20.0).abs() < 0.5, "followed again: {last}");
    node.assert_within_limits();
    // `shutdown` ends the run: a jerk-limited stop, then the end.
    node.command("shutdown");
    assert!(!node.run_for(2000, |_, _| {}), "shutdown ends the run");
    assert_eq!((node.run.finished)(), Some(Finish::Stopped));
    let c = &node.shared.counts;
    assert_eq!(c.commands.load(Ordering::Relaxed), 2, "stop and shutdown");
    assert_eq!(c.malformed.load(Ordering::Relaxed), 0);
}

#[test]
fn stop_during_a_motion_stops_it_where_it_is_and_holds() {
    let mut node = Node::new();
    node.command("play arm-wave");
    // Half a second into the wave (with its transition): moving.
    assert!(node.run_for(300, |_, _| {}));
    let moving = spread(&node.commanded[280..300]);
    assert!(moving > 0.5, "the wave moves: {moving}");
    node.command("stop");
    assert!(node.run_for(900, |_, _| {}), "the run goes on after stop");
    // Still within a second (the wave would have gone on), then held.
    assert!(spread(&node.commanded[500..]) < 1e-9, "held");
    node.assert_within_limits();
    // A motion plays again after a stop.
    node.command("play arm-wave");
    assert!(node.run_for(300, |_, _| {}));
    let len = node.commanded.len();
    assert!(spread(&node.commanded[len - 20..]) > 0.5, "plays again");
    assert_eq!((node.run.finished)(), None);
}

#[test]
fn chunks_are_followed_and_malformed_ones_never_move_the_robot() {
    let mut node = Node::new();
    assert!(node.run_for(40, |_, _| {}));
    let before = node.commanded.last().expect("cycles").clone();
    for bad in [
        r#"{"chunk": {"joints": {"shoulder_pan": [10, 20]}}}"#,
        r#"{"chunk": {"dt": 0, "joints": {"shoulder_pan": [10, 20]}}}"#,
        r#"{"chunk": {"dt": 0.02, "joints": {"shoulder_pan": [10, 20], "elbow_flex": [1]}}}"#,
        r#"{"chunk": {"dt": 0.02, "joints": {"shoulder_pan": ["far"]}}}"#,
        r#"{"chunk": [1, 2]}"#,
    ] {
        node.target(bad);
    }
    assert!(node.run_for(100, |_, _| {}));
    assert!(
        node.commanded[40..]
            .iter()
            .all(|r| r.iter().zip(&before).all(|(a, b)| (a - b).abs() < 1e-9)),
        "malformed chunks never move the robot"
    );
    let c = &node.shared.counts;
    assert_eq!(c.malformed.load(Ordering::Relaxed), 5);
    assert_eq!(c.chunks.load(Ordering::Relaxed), 0);
    // A chunk of 50 points at 50 Hz from where the pan is to +30 deg (on
    // arrival: no `t0`): the pan goes there along it.
    let from = before[PAN];
    let points: Vec<String> = (0..50)
        .map(|k| format!("{:.4}", from + (30.0 - from) * k as f64 / 49.0))
        .collect();
    node.target(&format!(
        r#"{{"chunk": {{"dt": 0.02, "joints": {{"shoulder_pan": [{}]}}}}}}"#,
        points.join(", ")
    ));
    assert!(node.run_for(400, |_, _| {}));
    assert_eq!(node.shared.counts.chunks.load(Ordering::Relaxed), 1);
    let pan = node.joint(PAN, 140);
    let mid = pan[100];
    assert!(mid > from + 5.0 && mid < 29.0, "on the way at 0.5 s: {mid}");
    let last = *pan.last().expect("cycles");
    assert!((last - 30.0).abs() < 0.5, "the chunk's end: {last}");
    node.assert_within_limits();
}

#[test]
fn a_base_velocity_for_an_arm_without_a_base_is_malformed_and_moves_nothing() {
    let mut node = Node::new();
    assert!(node.run_for(40, |_, _| {}));
    let before = node.commanded.last().expect("cycles").clone();
    // With a joint as well: refused whole, the joint not moved either.
    node.target(r#"{"joints": {"shoulder_pan": 20}, "base": {"x": 0.1}}"#);
    node.target(r#"{"base": {"w": 1}}"#);
    assert!(node.run_for(60, |_, _| {}));
    assert!(
        node.commanded[40..]
            .iter()
            .all(|r| r.iter().zip(&before).all(|(a, b)| (a - b).abs() < 1e-9)),
        "a refused base target never moves the robot"
    );
    assert_eq!(node.shared.counts.malformed.load(Ordering::Relaxed), 2);
}

#[test]
fn a_grasp_reaches_the_stream_and_one_it_cannot_make_is_refused() {
    let mut node = Node::new();
    assert!(node.run_for(20, |_, _| {}));
    node.target(r#"{"grasp": {"gripper": 40}}"#);
    node.target(r#"{"joints": {"shoulder_pan": 5}, "grasp": {"gripper": 25}}"#);
    let c = &node.shared.counts;
    assert_eq!(c.targets.load(Ordering::Relaxed), 2, "both grasps taken");
    // Well formed but not a grasp the gripper can make: the stream refuses
    // them (not counted as taken, nor malformed).
    node.target(r#"{"grasp": {"gripper": 150}}"#);
    node.target(r#"{"grasp": {"gripper": 0}}"#);
    node.target(r#"{"grasp": {"thumb": 40}}"#);
    assert_eq!(c.targets.load(Ordering::Relaxed), 2);
    assert_eq!(c.malformed.load(Ordering::Relaxed), 0);
    // A joint with an angle and a grasp is malformed: nothing is sent.
    node.target(r#"{"joints": {"gripper": 10}, "grasp": {"gripper": 40}}"#);
    node.target(r#"{"grasp": {"gripper": "firm"}}"#);
    assert_eq!(c.malformed.load(Ordering::Relaxed), 2);
    assert_eq!(c.targets.load(Ordering::Relaxed), 2);
    assert!(node.run_for(20, |_, _| {}));
}
