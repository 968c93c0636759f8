//! Forward kinematics of the SO-101 at hand-computed poses.
//!
//! Geometry (configs/robots/so101.yaml): pan axis at z 94.9; lift axis
//! 30.4 forward and 54.2 up from it; elbow 28.0 forward and 112.6 up from
//! the lift; wrist flex 134.9 forward and 5.2 up from the elbow; roll joint
//! 61.1 forward; tool 98.1 beyond it; gripper pivot 23.4 forward, 20.2
//! down from the roll joint. So at zero: pan (0, 0, 94.9), lift (30.4, 0,
//! 149.1), elbow (58.4, 0, 261.7), wrist flex (193.3, 0, 266.9), roll
//! (254.4, 0, 266.9), gripper (277.8, 0, 246.7), tool (352.5, 0, 266.9).

use servobus_kinematics::{Poses, Vector3};

use crate::robots::{pose, shipped, Shipped};

const MM: f64 = 1e-9;

fn frames(s: &Shipped, angles: &[(&str, f64)]) -> Poses {
    let mut out = Poses::new(&s.model);
    s.model.forward(&pose(s, angles), &mut out);
    out
}

fn at(s: &Shipped, p: &Poses, name: &str) -> Vector3<f64> {
    match s.model.frame_index(name) {
        Some(i) => p.frame(i).expect("frame").translation.vector,
        None => {
            let i = s.model.joint_index(name).expect("joint or frame");
            p.joint(i).expect("joint").translation.vector
        }
    }
}

fn assert_at(s: &Shipped, p: &Poses, name: &str, expected: [f64; 3]) {
    let got = at(s, p, name);
    let want = Vector3::from(expected);
    assert!(
        (got - want).norm() < 1e-6 + MM,
        "{name}: got {got:?}, expected {want:?}"
    );
}

fn assert_axis(s: &Shipped, p: &Poses, name: &str, local: [f64; 3], expected: [f64; 3]) {
    let i = s.model.frame_index(name).map_or_else(
        || p.joint(s.model.joint_index(name).expect("joint")),
        |i| p.frame(i),
    );
    let got = i.expect("pose").rotation * Vector3::from(local);
    assert!(
        (got - Vector3::from(expected)).norm() < 1e-9,
        "{name}: axis {local:?} went to {got:?}, expected {expected:?}"
    );
}

#[test]
fn so101_at_zero_is_the_calibration_pose() {
    let s = shipped("so101");
    let p = frames(&s, &[]);
    assert_at(&s, &p, "shoulder_pan", [0.0, 0.0, 94.9]);
    assert_at(&s, &p, "shoulder_lift", [30.4, 0.0, 149.1]);
    assert_at(&s, &p, "elbow_flex", [58.4, 0.0, 261.7]);
    assert_at(&s, &p, "wrist_flex", [193.3, 0.0, 266.9]);
    assert_at(&s, &p, "wrist_roll", [254.4, 0.0, 266.9]);
    assert_at(&s, &p, "gripper", [277.8, 0.0, 246.7]);
    assert_at(&s, &p, "tool", [352.5, 0.0, 266.9]);
    // Every frame is level and facing forward.
    assert_axis(&s, &p, "tool", [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
    assert_axis(&s, &p, "tool", [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]);
}

#[test]
fn so101_pan_90_turns_the_arm_to_the_left() {
    let s = shipped("so101");
    let p = frames(&s, &[("shoulder_pan", 90.0)]);
    assert_at(&s, &p, "shoulder_lift", [0.0, 30.4, 149.1]);
    assert_at(&s, &p, "tool", [0.0, 352.5, 266.9]);
    assert_axis(&s, &p, "tool", [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
}

#[test]
fn so101_lift_90_lays_the_arm_forward_and_down() {
    // About the lift axis (30.4, 0, 149.1), +90 about y: (x, z) -> (z, -x).
    // Elbow: (28, 112.6) -> (112.6, -28); tool: (322.1, 117.8) -> (117.8, -322.1).
    let s = shipped("so101");
    let p = frames(&s, &[("shoulder_lift", 90.0)]);
    assert_at(&s, &p, "elbow_flex", [143.0, 0.0, 121.1]);
    assert_at(&s, &p, "tool", [148.2, 0.0, -173.0]);
    assert_axis(&s, &p, "tool", [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]);
}

#[test]
fn so101_elbow_90_points_the_forearm_down() {
    // About the elbow (58.4, 0, 261.7): wrist (134.9, 5.2) -> (5.2, -134.9),
    // tool (294.1, 5.2) -> (5.2, -294.1).
    let s = shipped("so101");
    let p = frames(&s, &[("elbow_flex", 90.0)]);
    assert_at(&s, &p, "wrist_flex", [63.6, 0.0, 126.8]);
    assert_at(&s, &p, "tool", [63.6, 0.0, -32.4]);
    assert_axis(&s, &p, "tool", [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]);
}

#[test]
fn so101_wrist_flex_90_points_the_gripper_down() {
    let s = shipped("so101");
    let p = frames(&s, &[("wrist_flex", 90.0)]);
    assert_at(&s, &p, "wrist_roll", [193.3, 0.0, 205.8]);
    assert_at(&s, &p, "tool", [193.3, 0.0, 107.7]);
    assert_axis(&s, &p, "tool", [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]);
}

#[test]
fn so101_wrist_roll_90_turns_the_gripper_clockwise_seen_from_it() {
    // About -x: the gripper pivot's offset (0, -20.2) in (y, z) goes to
    // (-20.2, 0); the tool's y axis goes down.
    let s = shipped("so101");
    let p = frames(&s, &[("wrist_roll", 90.0)]);
    assert_at(&s, &p, "tool", [352.5, 0.0, 266.9]);
    assert_at(&s, &p, "gripper", [277.8, -20.2, 266.9]);
    assert_axis(&s, &p, "tool", [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]);
    let i = s.model.frame_index("tool").expect("tool");
    let (roll, pitch, yaw) = p.frame(i).expect("tool").rotation.euler_angles();
    assert!((roll + 90f64.to_radians()).abs() < 1e-9, "roll {roll}");
    assert!(pitch.abs() < 1e-9 && yaw.abs() < 1e-9);
}

#[test]
fn so101_gripper_90_turns_only_the_jaw() {
    let s = shipped("so101");
    let p = frames(&s, &[("gripper", 90.0)]);
    assert_at(&s, &p, "tool", [352.5, 0.0, 266.9]);
    assert_at(&s, &p, "gripper", [277.8, 0.0, 246.7]);
    assert_axis(&s, &p, "gripper", [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]);
}

#[test]
fn hexapod_home_feet_are_level_and_out_sideways() {
    // Femur 30 up, tibia 60 down from it: out 45 + 80 cos 30 + 160 cos 30
    // = 252.85, down 160 sin 30 - 80 sin 30 = 40.
    let s = shipped("hexapod");
    let mut angles = Vec::new();
    let names: Vec<String> = s.names.clone();
    for n in &names {
        if n.ends_with("_femur") {
            angles.push((n.as_str(), 30.0));
        } else if n.ends_with("_tibia") {
            angles.push((n.as_str(), -60.0));
        }
    }
    let p = frames(&s, &angles);
    let out = 45.0 + 240.0 * 30f64.to_radians().cos();
    assert_at(&s, &p, "foot_front_left", [110.0, 70.0 + out, -40.0]);
    assert_at(&s, &p, "foot_middle_right", [0.0, -90.0 - out, -40.0]);
    assert_at(&s, &p, "foot_rear_right", [-110.0, -70.0 - out, -40.0]);
}

#[test]
fn hexapod_coxa_forward_swings_both_sides_forward() {
    let s = shipped("hexapod");
    let p = frames(&s, &[("front_left_coxa", 90.0), ("front_right_coxa", 90.0)]);
    // Straight legs: 45 + 80 + 160 = 285 from the hip, now pointing +x.
    assert_at(&s, &p, "foot_front_left", [395.0, 70.0, 0.0]);
    assert_at(&s, &p, "foot_front_right", [395.0, -70.0, 0.0]);
}

#[test]
fn forward_allocates_nothing() {
    let s = shipped("hexapod");
    let mut out = Poses::new(&s.model);
    let q = vec![0.1; s.names.len()];
    let (count, ()) = servobus_alloc_count::allocations_during(|| s.model.forward(&q, &mut out));
    assert_eq!(count, 0);
}
