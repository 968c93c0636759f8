//! A motion keyframe's `grasp:`: the joint closes towards its `min` on the
//! way to the keyframe and grasps from the start of that move; a later
//! pose naming it ends the grasp. A grasp the joint cannot make is refused
//! with the file, line and column.

use servobus_config::{load_motion_text, KeyframeGrasp};

fn load(keyframes: &str) -> Result<servobus_config::Motion, String> {
    let text = format!("robot: lekiwi\nunits: deg\nkeyframes:\n{keyframes}");
    load_motion_text(std::path::Path::new("grasp.yaml"), &text, None, None)
        .map(|(m, _)| m)
        .map_err(|e| e.to_string())
}

#[test]
fn a_grasp_closes_the_joint_and_a_later_pose_naming_it_ends_it() {
    let m = load(
        "  - pose: {gripper: 40}\n  \
         - {grasp: {gripper: {effort: 35}}}\n  \
         - pose: {shoulder_pan: 10}\n  \
         - pose: {gripper: 50}\n",
    )
    .expect("loads");
    let gripper = 5;
    assert_eq!(m.keyframes[1].positions[gripper], 0.0, "closed: its min");
    assert_eq!(
        m.keyframes[1].grasps,
        vec![KeyframeGrasp {
            joint: gripper,
            effort: Some(35.0)
        }]
    );
    // A pose that does not name it keeps the grasp (and the closed goal).
    assert!(m.keyframes[2].grasps.is_empty());
    assert_eq!(m.keyframes[2].positions[gripper], 0.0);
    assert_eq!(
        m.keyframes[3].grasps,
        vec![KeyframeGrasp {
            joint: gripper,
            effort: None
        }]
    );
    assert!(m.keyframes[0].grasps.is_empty());
}

#[test]
fn a_grasp_the_joint_cannot_make_names_the_place() {
    for (keyframes, says) in [
        (
            "  - pose: {gripper: 40}\n  - {grasp: {thumb: {effort: 30}}}\n",
            "grasp.yaml:5:14: keyframes[1].grasp.thumb: no joint `thumb`",
        ),
        (
            "  - pose: {gripper: 40}\n  - {grasp: {gripper: {effort: 0}}}\n",
            "above 0 and at most 100, got 0",
        ),
        (
            "  - pose: {gripper: 40}\n  - {grasp: {gripper: {effort: 120}}}\n",
            "above 0 and at most 100, got 120",
        ),
        (
            "  - pose: {gripper: 40}\n  - {grasp: {wheel_left: {effort: 30}}}\n",
            "a wheel has nothing to close",
        ),
        (
            "  - pose: {gripper: 40}\n  - {pose: {gripper: 10}, grasp: {gripper: {effort: 30}}}\n",
            "the pose gives it a position too",
        ),
        (
            "  - pose: {gripper: 40}\n  - {grasp: {gripper: {force: 30}}}\n",
            "unknown field `force`",
        ),
    ] {
        let e = load(keyframes).expect_err(keyframes);
        assert!(e.contains(says), "{keyframes}: {e}");
    }
}
