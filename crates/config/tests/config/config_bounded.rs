//! Generators that expand a few lines of a motion into samples (`walk:`,
//! `body:`, `path: line`) count their samples before they make them, and
//! every number that sizes them has a range: a small file cannot ask for
//! unbounded memory, and each refusal names the file, line and field.

use std::path::{Path, PathBuf};

use crate::common;
use servobus_config::{load_motion, ConfigError};

/// The hexapod's standing pose, as the shipped motions give it.
const STAND: &str = "\
poses:
  stand:
    {front_left_coxa: 0, front_left_femur: 30, front_left_tibia: -60,
     middle_left_coxa: 0, middle_left_femur: 30, middle_left_tibia: -60,
     rear_left_coxa: 0, rear_left_femur: 30, rear_left_tibia: -60,
     front_right_coxa: 0, front_right_femur: 30, front_right_tibia: -60,
     middle_right_coxa: 0, middle_right_femur: 30, middle_right_tibia: -60,
     rear_right_coxa: 0, rear_right_femur: 30, rear_right_tibia: -60}
keyframes:
  - pose: stand
";

/// A hexapod motion: `STAND` then `rest` (keyframes after the first, and
/// any top-level fields after them).
fn hexapod(test: &str, rest: &str) -> PathBuf {
    let robot = common::config("robots/hexapod.yaml");
    let text = format!("robot: {}\nunits: deg\n{STAND}{rest}", robot.display());
    common::temp_file(&format!("config_bounded/{test}"), "motion.yaml", &text)
}

/// An SO-101 motion from its rest pose, then `rest`.
fn arm(test: &str, rest: &str) -> PathBuf {
    let robot = common::config("robots/so101.yaml");
    let text = format!(
        "robot: {}\nunits: deg\nkeyframes:\n  - pose: {{shoulder_pan: 0, shoulder_lift: -90, \
         elbow_flex: 90, wrist_flex: 45, wrist_roll: 0, gripper: 10}}\n  - tool: {{xyz: [220, \
         60, 120], pitch: 60}}\n{rest}",
        robot.display()
    );
    common::temp_file(&format!("config_bounded/{test}"), "motion.yaml", &text)
}

/// The refusal of `path`, which must start `path:line:column: field: `
/// and contain every one of `words`.
fn refused(path: &Path, line: usize, field: &str, words: &[&str]) -> ConfigError {
    let e = load_motion(path, None).expect_err("the motion must be refused");
    let text = e.to_string();
    let prefix = format!("{}:{line}:", path.display());
    assert!(
        text.starts_with(&prefix),
        "`{text}` should start `{prefix}`"
    );
    assert_eq!(e.field(), Some(field), "{text}");
    for w in words {
        assert!(text.contains(w), "`{text}` should say `{w}`");
    }
    e
}

#[test]
fn a_walk_period_outside_its_range_is_refused_with_the_range() {
    for period in ["1e-9", "0", "-1", "0.1", ".nan", ".inf", "1e300"] {
        let p = hexapod(
            "period",
            &format!(
                "  - walk: {{gait: tripod, lift: 20, period: {period}, segments: \
                 [{{velocity: [20, 0], duration: 2}}]}}\n"
            ),
        );
        refused(
            &p,
            13,
            "keyframes[1].walk.period",
            &["must be a step period from 0.2 to 3600 s"],
        );
    }
}

#[test]
fn a_walk_with_more_samples_than_the_plan_has_room_for_is_refused_before_it_is_made() {
    // 3000 s sampled every 20 ms is 150,000 poses of 18 joints: 2.7 million
    // segments against the limit of 500,000 (room for 27,777 poses).
    let p = hexapod(
        "long-walk",
        "  - walk: {gait: tripod, lift: 20, period: 2, segments: [{velocity: [0, 0], duration: \
         3000}]}\n",
    );
    refused(
        &p,
        13,
        "keyframes[1].walk",
        &[
            "keyframe 1: this walk",
            "150201 samples",
            "room for 27776 more",
        ],
    );
    // Repeated, the same walk's room shrinks with the repetitions.
    let p = hexapod(
        "repeated-walk",
        "  - walk: {gait: tripod, lift: 20, period: 2, segments: [{velocity: [0, 0], duration: \
         300}]}\nrepeat: 10\n",
    );
    refused(&p, 13, "keyframes[1].walk", &["room for 2776 more"]);
}

#[test]
fn a_walk_of_too_many_segments_is_refused() {
    let segments = vec!["{velocity: [10, 0], duration: 0.5}"; 1001].join(", ");
    let p = hexapod(
        "segments",
        &format!("  - walk: {{gait: tripod, lift: 20, period: 2, segments: [{segments}]}}\n"),
    );
    refused(
        &p,
        13,
        "keyframes[1].walk.segments",
        &["1001 segments: a walk may have 1 to 1000"],
    );
}

#[test]
fn a_body_below_the_ground_is_refused() {
    for height in ["-100", "0"] {
        let p = hexapod("height", &format!("  - body: {{height: {height}}}\n"));
        refused(
            &p,
            13,
            "keyframes[1].body.height",
            &[&format!(
                "must be a height above the ground, > 0 mm, got {height}"
            )],
        );
    }
    // A height above the ground still stands.
    let p = hexapod("height-ok", "  - body: {height: 60}\n");
    load_motion(&p, None).expect("a body raised to 60 mm");
}

#[test]
fn a_slow_body_move_is_counted_before_it_is_sampled() {
    // 30 mm at 0.03 mm/s: 1000 s, 50,000 poses, room for 27,777.
    let p = hexapod(
        "slow-body",
        "  - body: {shift: [30, 0]}\n    max_speed: 0.03\n",
    );
    refused(
        &p,
        13,
        "keyframes[1].body",
        &["keyframe 1: this body move", "room for 27776 more"],
    );
}

#[test]
fn a_line_tolerance_outside_its_range_is_refused_with_the_range() {
    for tolerance in ["1e-9", "0", "-1", "1000", ".nan"] {
        let p = arm(
            "tolerance",
            &format!(
                "  - tool: {{xyz: [220, 60, 70], pitch: 60}}\n    path: line\n    tolerance: \
                 {tolerance}\n"
            ),
        );
        refused(
            &p,
            8,
            "keyframes[2].tolerance",
            &["must be a distance from 0.01 to 100 mm"],
        );
    }
}

#[test]
fn a_slow_line_is_counted_before_it_is_sampled() {
    // 50 mm at 0.025 mm/s: a little over 2000 s, 40,002 samples every
    // 50 ms; repeated three times the six joints have room for 27,777
    // poses, two of them the keyframes before.
    let line = "  - tool: {xyz: [220, 60, 70], pitch: 60}\n    path: line\n    max_speed: 0.025\n";
    let p = arm("slow-line", &format!("{line}repeat: 3\n"));
    refused(
        &p,
        6,
        "keyframes[2].tool",
        &[
            "keyframe 2: this line would make 40002 samples",
            "room for 27775 more",
        ],
    );
}

#[test]
fn the_planner_speaks_of_joints_by_name_in_the_files_units() {
    // A body move far faster than the legs' servos can follow.
    let p = hexapod(
        "fast-body",
        "  - body: {height: 70}\n    max_speed: 2000\n    max_acceleration: 100000\n    \
         max_jerk: 10000000\n",
    );
    let e = refused(
        &p,
        13,
        "keyframes[1].body",
        &[
            "keyframe 1: the legs cannot follow this body move",
            " deg/s",
            "s into the move",
        ],
    );
    let text = e.to_string();
    assert!(text.contains("joint `"), "{text}");
    assert!(
        !text.contains("joint 0") && !text.contains(" rad"),
        "{text}"
    );
}

/// The cases of the bad-input corpus (`tests/bad_inputs/`) this module's
/// rules refuse, each with the start of its message after the file name.
#[test]
fn the_corpus_cases_are_refused_where_they_go_wrong() {
    let corpus = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/bad_inputs");
    for (file, expected) in [
        (
            "motion-walk-period-tiny.yaml",
            ":13:44: keyframes[1].walk.period: must be a step period from 0.2 to 3600 s, got 1e-9",
        ),
        (
            "motion-walk-long.yaml",
            ":13:11: keyframes[1].walk: keyframe 1: this walk would make 150201 samples",
        ),
        (
            "motion-body-below-ground.yaml",
            ":13:20: keyframes[1].body.height: keyframe 1: must be a height above the ground, > 0 \
             mm, got -100",
        ),
        (
            "motion-line-tolerance-tiny.yaml",
            ":8:16: keyframes[2].tolerance: must be a distance from 0.01 to 100 mm, got 1e-9",
        ),
    ] {
        let path = corpus.join(file);
        let e = load_motion(&path, None).expect_err(file);
        let text = e.to_string();
        let rest = text
            .strip_prefix(&path.display().to_string())
            .unwrap_or(&text);
        assert!(rest.starts_with(expected), "{file}: `{text}`");
    }
}
