//! Forward kinematics of the SO-101 at hand-computed poses.
//!
//! Geometry (configs/robots/so101.yaml): pan axis at z 64.8; lift axis
//! 30.4 forward, 18.28 right and 54.2 up from it; elbow 28.0 forward and
//! 112.57 up from the lift; wrist flex 134.9 forward and 5.2 up from the
//! elbow; roll joint 61.1 forward and 18.1 left; tool 98.13 beyond it,
//! 0.17 left and 7.9 down, rolled 2.789 deg (and 0.001 deg of pitch and
//! yaw); gripper axis 23.4 forward, 17.79 left and 21.09 up from the roll
//! joint. So at zero: pan (0, 0, 64.8), lift (30.4, -18.28, 119.0), elbow
//! (58.4, -18.28, 231.57), wrist flex (193.3, -18.28, 236.77), roll
//! (254.4, -0.18, 236.77), gripper (277.8, 17.61, 257.86), tool (352.53,
//! -0.01, 228.87).

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

/// The tool's 0.001 deg of pitch and yaw (1.7e-5 rad) and the gripper
/// axis's six figures are within this of the axes worked out by hand.
const AXIS: f64 = 1e-4;

fn assert_axis(s: &Shipped, p: &Poses, name: &str, local: [f64; 3], expected: [f64; 3]) {
    let i = s.model.frame_index(name).map_or_else(
        || p.joint(s.model.joint_index(name).expect("joint")),
        |i| p.frame(i),
    );
    let got = i.expect("pose").rotation * Vector3::from(local);
    assert!(
        (got - Vector3::from(expected)).norm() < AXIS,
        "{name}: axis {local:?} went to {got:?}, expected {expected:?}"
    );
}

/// sin and cos of the tool's roll about the roll axis, 2.789 deg.
fn tilt() -> (f64, f64) {
    2.789f64.to_radians().sin_cos()
}

#[test]
fn so101_at_zero_is_the_calibration_pose() {
    let s = shipped("so101");
    let p = frames(&s, &[]);
    assert_at(&s, &p, "shoulder_pan", [0.0, 0.0, 64.8]);
    assert_at(&s, &p, "shoulder_lift", [30.4, -18.28, 119.0]);
    assert_at(&s, &p, "elbow_flex", [58.4, -18.28, 231.57]);
    assert_at(&s, &p, "wrist_flex", [193.3, -18.28, 236.77]);
    assert_at(&s, &p, "wrist_roll", [254.4, -0.18, 236.77]);
    assert_at(&s, &p, "gripper", [277.8, 17.61, 257.86]);
    assert_at(&s, &p, "tool", [352.53, -0.01, 228.87]);
    // The tool faces forward, rolled 2.789 deg: its z axis leans right.
    let (sin, cos) = tilt();
    assert_axis(&s, &p, "tool", [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
    assert_axis(&s, &p, "tool", [0.0, 0.0, 1.0], [0.0, -sin, cos]);
    // Every joint's frame is level and facing forward.
    assert_axis(&s, &p, "wrist_roll", [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]);
}

#[test]
fn so101_pan_90_turns_the_arm_to_the_left() {
    // About z: (x, y) -> (-y, x).
    let s = shipped("so101");
    let p = frames(&s, &[("shoulder_pan", 90.0)]);
    assert_at(&s, &p, "shoulder_lift", [18.28, 30.4, 119.0]);
    assert_at(&s, &p, "tool", [0.01, 352.53, 228.87]);
    assert_axis(&s, &p, "tool", [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
}

#[test]
fn so101_lift_90_lays_the_arm_forward_and_down() {
    // About the lift axis (30.4, -18.28, 119.0), +90 about y: (x, z) ->
    // (z, -x). Elbow: (28, 112.57) -> (112.57, -28); tool: (322.13,
    // 109.87) -> (109.87, -322.13).
    let s = shipped("so101");
    let p = frames(&s, &[("shoulder_lift", 90.0)]);
    assert_at(&s, &p, "elbow_flex", [142.97, -18.28, 91.0]);
    assert_at(&s, &p, "tool", [140.27, -0.01, -203.13]);
    assert_axis(&s, &p, "tool", [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]);
}

#[test]
fn so101_elbow_90_points_the_forearm_down() {
    // About the elbow (58.4, -18.28, 231.57): wrist (134.9, 5.2) -> (5.2,
    // -134.9), tool (294.13, -2.7) -> (-2.7, -294.13).
    let s = shipped("so101");
    let p = frames(&s, &[("elbow_flex", 90.0)]);
    assert_at(&s, &p, "wrist_flex", [63.6, -18.28, 96.67]);
    assert_at(&s, &p, "tool", [55.7, -0.01, -62.56]);
    assert_axis(&s, &p, "tool", [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]);
}

#[test]
fn so101_wrist_flex_90_points_the_gripper_down() {
    // About the wrist flex axis (193.3, -18.28, 236.77): roll joint (61.1,
    // 0) -> (0, -61.1), tool (159.23, -7.9) -> (-7.9, -159.23).
    let s = shipped("so101");
    let p = frames(&s, &[("wrist_flex", 90.0)]);
    assert_at(&s, &p, "wrist_roll", [193.3, -0.18, 175.67]);
    assert_at(&s, &p, "tool", [185.4, -0.01, 77.54]);
    assert_axis(&s, &p, "tool", [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]);
}

#[test]
fn so101_wrist_roll_90_turns_the_gripper_clockwise_seen_from_it() {
    // About -x through the roll joint (254.4, -0.18, 236.77): offsets (y,
    // z) go to (z, -y). The tool's (0.17, -7.9) goes to (-7.9, -0.17), the
    // gripper axis's (17.79, 21.09) to (21.09, -17.79). The tool's y axis,
    // (0, cos, sin) of its 2.789 deg roll, goes to (0, sin, -cos): down,
    // leaning 2.789 deg to the left; its roll is 2.789 - 90 deg.
    let s = shipped("so101");
    let p = frames(&s, &[("wrist_roll", 90.0)]);
    assert_at(&s, &p, "tool", [352.53, -8.08, 236.6]);
    assert_at(&s, &p, "gripper", [277.8, 20.91, 218.98]);
    let (sin, cos) = tilt();
    assert_axis(&s, &p, "tool", [0.0, 1.0, 0.0], [0.0, sin, -cos]);
    let i = s.model.frame_index("tool").expect("tool");
    let (roll, pitch, yaw) = p.frame(i).expect("tool").rotation.euler_angles();
    assert!(
        (roll - (2.789 - 90.0f64).to_radians()).abs() < AXIS,
        "roll {roll}"
    );
    assert!(pitch.abs() < AXIS && yaw.abs() < AXIS, "{pitch} {yaw}");
}

#[test]
fn so101_gripper_90_turns_only_the_jaw() {
    // The gripper axis (0, -0.998815, -0.048663) is about -y: at +90 the
    // jaw's x axis goes to axis x (1, 0, 0) = (0, -0.048663, 0.998815),
    // up: the moving jaw on top opens upwards.
    let s = shipped("so101");
    let p = frames(&s, &[("gripper", 90.0)]);
    assert_at(&s, &p, "tool", [352.53, -0.01, 228.87]);
    assert_at(&s, &p, "gripper", [277.8, 17.61, 257.86]);
    assert_axis(
        &s,
        &p,
        "gripper",
        [1.0, 0.0, 0.0],
        [0.0, -0.048663, 0.998815],
    );
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
