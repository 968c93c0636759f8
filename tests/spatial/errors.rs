//! Spatial keyframes that cannot be done are refused when the motion
//! loads, at the keyframe's line and column, with the reason.

use std::path::PathBuf;

use servobus_runtime::config::load_motion;

use crate::config;

/// Writes a motion for the shipped robot `robot` (keyframes as given) to a
/// scratch file, loads it and returns the error's text.
fn refused(name: &str, robot: &str, keyframes: &str) -> String {
    let dir = std::env::temp_dir().join(format!("servobus-spatial-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    let path: PathBuf = dir.join(name);
    let robot = config(&format!("robots/{robot}.yaml"));
    let text = format!(
        "robot: {}\nunits: deg\nkeyframes:\n{keyframes}",
        robot.display()
    );
    std::fs::write(&path, text).expect("writes");
    let err = load_motion(&path, None).expect_err("refused");
    err.to_string()
}

const ARM_START: &str = "  - pose: {shoulder_lift: -90, elbow_flex: 90, wrist_flex: 45}\n";

#[test]
fn a_line_to_the_stretched_arm_is_refused_at_its_keyframe_as_a_singularity() {
    // At the lift axis's height, pitched up 2.84 deg so that the tool,
    // 7.9 below the roll axis, lines up with the arm stretched straight,
    // out to 0.1 mm short of full reach (see the kinematics crate's test
    // of the same line).
    let text = refused(
        "stretched.yaml",
        "so101",
        &format!(
            "{ARM_START}  - tool: {{xyz: [250, 0, 119], pitch: -2.84}}\n  \
             - tool: {{xyz: [440.73, 0, 119], pitch: -2.84}}\n    path: line\n"
        ),
    );
    assert!(
        text.contains(":6:11: keyframes[2].tool: keyframe 2:"),
        "{text}"
    );
    assert!(text.contains("near a singularity"), "{text}");
}

#[test]
fn a_line_out_of_reach_is_refused_with_the_distance_short() {
    let text = refused(
        "far.yaml",
        "so101",
        &format!("{ARM_START}  - tool: {{xyz: [600, 0, 149.1]}}\n    path: line\n"),
    );
    assert!(
        text.contains(":5:11: keyframes[1].tool: keyframe 1:"),
        "{text}"
    );
    assert!(text.contains("out of reach"), "{text}");
}

#[test]
fn a_first_keyframe_cannot_be_a_line_or_a_walk() {
    let text = refused(
        "first.yaml",
        "so101",
        "  - tool: {xyz: [250, 0, 149.1]}\n    path: line\n",
    );
    assert!(
        text.contains("keyframes[0]: keyframe 0: the first keyframe is the start"),
        "{text}"
    );
}

#[test]
fn a_walk_needs_feet() {
    let text = refused(
        "armwalk.yaml",
        "so101",
        &format!(
            "{ARM_START}  - walk: {{gait: tripod, lift: 20, period: 2, segments: \
             [{{velocity: [10, 0], duration: 1}}]}}\n"
        ),
    );
    assert!(
        text.contains("keyframes[1].walk: keyframe 1: no frame `foot_<leg>`"),
        "{text}"
    );
}

#[test]
fn a_walk_too_fast_for_its_stride_names_the_segment() {
    let stand = "  - pose: {front_left_femur: 30, front_left_tibia: -60, middle_left_femur: 30, \
                 middle_left_tibia: -60, rear_left_femur: 30, rear_left_tibia: -60, \
                 front_right_femur: 30, front_right_tibia: -60, middle_right_femur: 30, \
                 middle_right_tibia: -60, rear_right_femur: 30, rear_right_tibia: -60}\n";
    // Tripod: feet down half of 2 s; 80 mm/s sweeps 80 mm, over 60.
    let text = refused(
        "fast.yaml",
        "hexapod",
        &format!(
            "{stand}  - walk: {{gait: tripod, stride: 60, lift: 20, period: 2, segments: \
             [{{velocity: [20, 0], duration: 2}}, {{velocity: [80, 0], duration: 2}}]}}\n"
        ),
    );
    assert!(
        text.contains("segment 1 needs a stride of 80.0 mm, more than the stride 60.0 mm"),
        "{text}"
    );
}
