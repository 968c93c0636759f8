//! `servobus serve --ros2` taking ROS 2 in, on loopback: a client written
//! without ROS (tests/zenoh/ros2_client.py: eclipse-zenoh, and rosbags'
//! CDR serializer for the messages) sends JointTrajectory and JointState
//! on rmw_zenoh's keys and calls the FollowJointTrajectory action's
//! services the way rmw_zenoh's clients do; a Rust peer does the same
//! with servobus's own encoder. A module of serve_cli.rs (its helpers).

use std::process::Command;
use std::time::{Duration, Instant};

use servobus_node::ros2::{self, CdrMessage, JointTrajectory, JointTrajectoryPoint, RosDuration};
use servobus_node::zenoh::Wait;

use super::common::{self, Running};
use super::{endpoint, free_port, last_json, peer, serial, wait_for_state, zenoh_python};

/// Runs `tests/zenoh/ros2_client.py SCENARIO` against a node on `ep`
/// (ROS domain 7, namespace `ns`); returns the client's summary after
/// checking it failed nothing.
fn client(ep: &str, ns: &str, scenario: &str, serve: Running) -> (serde_json::Value, String) {
    let out = Command::new(zenoh_python())
        .arg(common::repo("tests/zenoh/ros2_client.py"))
        .args([ep, "so101", "7", ns, scenario])
        .output()
        .expect("run the Python client");
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    println!("{text}{}", String::from_utf8_lossy(&out.stderr));
    let (status, stdout, stderr) = serve.finish();
    assert!(
        out.status.success(),
        "the client failed:\n{text}\nserve: {stderr}"
    );
    assert!(!text.contains("FAIL"), "{text}");
    assert!(status.success(), "serve: {stderr}");
    let summary = serde_json::from_str(text.lines().last().unwrap_or_default()).expect("summary");
    (summary, stdout)
}

fn serve(ep: &str, extra: &[&str]) -> Running {
    let mut args = vec![
        "serve",
        "--robot",
        "so101",
        "--listen",
        ep,
        "--ros2",
        "--ros-domain",
        "7",
        "--linger",
        "2",
        "--json",
    ];
    args.extend_from_slice(extra);
    Running::start(&args)
}

#[test]
#[ignore = "needs a Python with eclipse-zenoh: see NEEDS_ZENOH_PYTHON"]
fn ros2_trajectories_and_joint_commands_move_the_arm_and_malformed_cdr_moves_nothing() {
    let _one = serial();
    let ep = endpoint(free_port());
    // Every cycle's state, to see the path at each point's time.
    let node = serve(&ep, &["--state-hz", "200"]);
    let (summary, stdout) = client(&ep, "so101", "topics", node);
    let doc = last_json(&stdout);
    assert_eq!(doc["node"]["malformed"], 11, "{doc}");
    assert_eq!(doc["node"]["trajectories"], 3, "{doc}");
    assert!(
        summary["four_points_measured_deg"].as_f64() < Some(1.0),
        "{summary}"
    );
    // JointState and Float64MultiArray are targets of the stream: counted,
    // latency from their stamps, the stop and resume of its rules.
    assert_eq!(doc["report"]["live"]["refused"], 0, "{doc}");
    assert!(
        doc["report"]["live"]["received"].as_u64() > Some(60),
        "{doc}"
    );
}

#[test]
#[ignore = "needs a Python with eclipse-zenoh: see NEEDS_ZENOH_PYTHON"]
fn ros2_follow_joint_trajectory_succeeds_with_feedback_cancels_and_refuses_with_a_reason() {
    let _one = serial();
    let ep = endpoint(free_port());
    // Where a MoveIt controller looks for it: /arm_controller/follow_joint_trajectory.
    let node = serve(
        &ep,
        &["--state-hz", "200", "--ros-namespace", "arm_controller"],
    );
    let (summary, stdout) = client(&ep, "arm_controller", "action", node);
    let doc = last_json(&stdout);
    assert_eq!(doc["node"]["goals"], 2, "{doc}");
    assert_eq!(doc["node"]["malformed"], 4, "{doc}");
    let hz = summary["feedback_hz"].as_f64().unwrap_or_default();
    assert!(
        (150.0..250.0).contains(&hz),
        "feedback at the state rate: {hz} Hz"
    );
}

#[test]
#[ignore = "needs a Python with eclipse-zenoh: see NEEDS_ZENOH_PYTHON"]
fn ros2_a_joint_stalled_on_a_stop_breaks_its_path_tolerance_and_the_goal_aborts() {
    let _one = serial();
    let dir = common::scratch("serve-ros2-stall");
    // The simulated pan meets a mechanical stop at 15 deg.
    let mounting = common::write_file(
        &dir,
        "mounting.yaml",
        "shoulder_pan: {zero_tick: 2048, direction: 1, stops: [-115, 15]}\n",
    );
    let sim = common::Sim::start_with(&dir, &["--mounting", common::arg(&mounting)]);
    let ep = endpoint(free_port());
    let node = serve(&ep, &["--port", common::arg(&sim.link)]);
    let (_, stdout) = client(&ep, "so101", "stall", node);
    assert_eq!(last_json(&stdout)["node"]["goals"], 1, "{stdout}");
    drop(sim);
}

#[test]
#[ignore = "needs a Python with eclipse-zenoh: see NEEDS_ZENOH_PYTHON"]
fn ros2_latency_from_a_published_trajectory_to_its_first_goal_on_the_wire() {
    let _one = serial();
    let ep = endpoint(free_port());
    let node = serve(&ep, &[]);
    let (summary, _) = client(&ep, "so101", "latency", node);
    let lat = &summary["latency_ms"];
    println!(
        "latency, JointTrajectory published -> first goal on the wire (loopback, 200 Hz): \
         p50 {} ms, p99 {} ms",
        lat["p50"], lat["p99"]
    );
    assert!(lat["p99"].as_f64() < Some(50.0), "{lat}");
}

/// A JointTrajectory of `joint` through `points` (rad, s from now).
fn trajectory(joint: &str, points: &[(f64, f64)]) -> Vec<u8> {
    JointTrajectory {
        joint_names: vec![joint.into()],
        points: points
            .iter()
            .map(|&(q, t)| JointTrajectoryPoint {
                positions: vec![q],
                time_from_start: RosDuration::from_secs_f64(t),
                ..Default::default()
            })
            .collect(),
        ..Default::default()
    }
    .encode()
}

/// The newest commanded angle of `joint` on `state` (deg), waiting for it.
fn commanded(session: &servobus_node::zenoh::Session, joint: &str) -> f64 {
    let sub = session
        .declare_subscriber("servobus/so101/state")
        .wait()
        .expect("subscribe");
    let sample = sub
        .recv_timeout(Duration::from_secs(10))
        .ok()
        .flatten()
        .expect("a state");
    let doc: serde_json::Value =
        serde_json::from_slice(&sample.payload().to_bytes()).expect("JSON");
    let names = doc["joints"].as_array().expect("joints");
    let j = names.iter().position(|n| n == joint).expect("the joint");
    doc["commanded"][j].as_f64().expect("an angle")
}

#[test]
fn ros2_a_rust_peer_moves_the_arm_by_trajectory_and_malformed_cdr_moves_nothing() {
    let _one = serial();
    let ep = endpoint(free_port());
    let node = serve(&ep, &[]);
    let peer = peer(std::slice::from_ref(&ep), &[]);
    assert!(wait_for_state(&peer, "so101"), "the node serves");
    let key = ros2::joint_trajectory_key(7, "so101");
    std::thread::sleep(Duration::from_millis(300));
    let before = commanded(&peer, "wrist_flex");
    for bad in [
        b"\x00\x01\x00\x00garbage".to_vec(),
        trajectory("thumb", &[(0.5, 1.0)]),
    ] {
        peer.put(&key, bad).wait().expect("put");
    }
    std::thread::sleep(Duration::from_millis(500));
    let after = commanded(&peer, "wrist_flex");
    assert!(
        (after - before).abs() < 1e-9,
        "malformed CDR moved the wrist: {before} -> {after}"
    );
    // 30 deg in a second: the wrist goes there along it and stays.
    let goal = before + 30.0;
    let traj = trajectory("wrist_flex", &[(goal.to_radians(), 1.0)]);
    peer.put(&key, traj).wait().expect("put");
    let deadline = Instant::now() + Duration::from_secs(10);
    while (commanded(&peer, "wrist_flex") - goal).abs() > 0.1 {
        assert!(Instant::now() < deadline, "the trajectory never got there");
        std::thread::sleep(Duration::from_millis(50));
    }
    peer.put("servobus/so101/command", "shutdown")
        .wait()
        .expect("shutdown");
    let (status, stdout, stderr) = node.finish();
    assert!(status.success(), "{stderr}");
    let doc = last_json(&stdout);
    assert_eq!(doc["node"]["malformed"], 2, "{doc}");
    assert_eq!(doc["node"]["trajectories"], 1, "{doc}");
    assert!(stderr.contains("no joint is named `thumb`"), "{stderr}");
}
