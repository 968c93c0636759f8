//! A joint's `faults:`: what loads, its defaults, and what is refused,
//! where and why.

use std::path::Path;

use super::*;

fn from_text(text: &str) -> Result<Robot, crate::ConfigError> {
    let source = RobotSource::Text {
        name: Path::new("<text>"),
        text,
    };
    load_robot(source, &RobotOptions::default())
}

/// A robot in `units` with a position joint `arm` (lines 6..=12) and a
/// joint `gripper` (ID 2, from line 13) whose lines after `id:` are
/// `rest`, each indented by 8: the first of them is on line 15.
fn robot(units: &str, rest: &[&str]) -> String {
    let mut text = format!(
        "name: r\nunits: {units}\nbuses:\n  - name: b\n    joints:\n      - name: arm\n        \
         id: 1\n        model: sts3215\n        min: -1.5\n        max: 1.5\n        \
         max_velocity: 3\n        max_acceleration: 15\n      - name: gripper\n        id: 2\n"
    );
    for line in rest {
        text.push_str("        ");
        text.push_str(line);
        text.push('\n');
    }
    text
}

/// A position gripper with `faults` (a line such as `faults: {stall: hold}`).
fn gripper(faults: &str) -> String {
    robot(
        "deg",
        &[
            "model: sts3215",
            "min: 0",
            "max: 100",
            "max_velocity: 240",
            "max_acceleration: 1500",
            faults,
        ],
    )
}

fn faults_of(text: &str, joint: &str) -> JointFaults {
    let r = from_text(text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    r.joint(joint).expect("the joint").faults
}

/// The one-line error of `text`, which must start `<text>:line:col: field: `
/// and hold every one of `words`.
fn refused(text: &str, (line, column): (usize, usize), field: &str, words: &[&str]) {
    let message = from_text(text).expect_err(text).to_string();
    let prefix = format!("<text>:{line}:{column}: {field}: ");
    assert!(
        message.starts_with(&prefix),
        "`{message}`, expected `{prefix}`"
    );
    for w in words {
        assert!(message.contains(w), "`{message}` does not say `{w}`");
    }
    assert!(!message.contains('\n'), "one line: {message}");
}

#[test]
fn without_faults_every_joint_takes_the_run_wide_policy() {
    let text = gripper("home: 10");
    for joint in ["arm", "gripper"] {
        let f = faults_of(&text, joint);
        assert_eq!(f, JointFaults::default());
        assert_eq!(f.stall, FaultResponse::Fault);
        assert_eq!(f.following_error, FaultResponse::Fault);
        assert_eq!(f.following_tolerance, None);
    }
}

#[test]
fn a_gripper_may_hold_a_stall_and_ignore_its_following_error() {
    let text = gripper("faults: {following_error: ignore, stall: hold}");
    let f = faults_of(&text, "gripper");
    assert_eq!(f.stall, FaultResponse::Hold);
    assert_eq!(f.following_error, FaultResponse::Ignore);
    assert_eq!(f.following_tolerance, None);
    // The other joint keeps the defaults.
    assert_eq!(faults_of(&text, "arm"), JointFaults::default());
}

#[test]
fn each_key_is_optional_and_a_block_mapping_works_too() {
    let f = faults_of(&gripper("faults: {stall: ignore}"), "gripper");
    assert_eq!(
        (f.stall, f.following_error),
        (FaultResponse::Ignore, FaultResponse::Fault)
    );
    let text =
        gripper("faults:\n          following_error: hold\n          following_tolerance: 25");
    let f = faults_of(&text, "gripper");
    assert_eq!(
        (f.stall, f.following_error, f.following_tolerance),
        (FaultResponse::Fault, FaultResponse::Hold, Some(25.0))
    );
    // `fault` is the default, said out loud; `{}` is no change.
    let f = faults_of(
        &gripper("faults: {stall: fault, following_error: fault}"),
        "gripper",
    );
    assert_eq!(f, JointFaults::default());
    assert_eq!(
        faults_of(&gripper("faults: {}"), "gripper"),
        JointFaults::default()
    );
}

#[test]
fn the_tolerance_is_in_the_files_units() {
    let text = robot(
        "rad",
        &[
            "model: sts3215",
            "min: 0",
            "max: 1.5",
            "max_velocity: 4",
            "max_acceleration: 20",
            "faults: {following_tolerance: 0.3}",
        ],
    );
    assert_eq!(faults_of(&text, "gripper").following_tolerance, Some(0.3));
}

#[test]
fn heat_current_status_and_a_missing_servo_are_refused_as_keys() {
    // `faults: {` is at column 9 of line 20; its first key at column 18.
    for key in ["overheat", "heat", "current", "status", "missing", "stal"] {
        let text = gripper(&format!("faults: {{{key}: hold}}"));
        refused(
            &text,
            (20, 18),
            "buses[0].joints[1].faults",
            &[
                &format!("unknown field `{key}`"),
                "`following_error`, `stall` and `following_tolerance`",
                "heat, over-current",
                "missing servo",
                "always end the run",
            ],
        );
    }
}

#[test]
fn an_unknown_reaction_is_refused_naming_the_three() {
    let text = gripper("faults: {stall: stop}");
    let message = from_text(&text)
        .expect_err("stop is a run-wide reaction")
        .to_string();
    assert!(message.starts_with("<text>:20:"), "{message}");
    for w in [
        "buses[0].joints[1].faults.stall",
        "`stop`",
        "`fault`",
        "`hold`",
        "`ignore`",
    ] {
        assert!(message.contains(w), "`{message}` does not say {w}");
    }
}

#[test]
fn a_key_given_twice_is_refused() {
    let text = gripper("faults: {stall: hold, stall: ignore}");
    let message = from_text(&text).expect_err("twice").to_string();
    assert!(message.contains("duplicate field `stall`"), "{message}");
    assert!(message.starts_with("<text>:20:"), "{message}");
}

#[test]
fn a_tolerance_must_be_a_positive_angle() {
    for bad in ["0", "-5", ".nan", ".inf"] {
        let text = gripper(&format!("faults: {{following_tolerance: {bad}}}"));
        refused(
            &text,
            (20, 39),
            "buses[0].joints[1].faults.following_tolerance",
            &["must be a positive angle"],
        );
    }
}

#[test]
fn a_wheel_has_no_faults_to_set() {
    let text = robot(
        "deg",
        &[
            "model: sts3215",
            "mode: wheel",
            "max_velocity: 200",
            "max_acceleration: 400",
            "faults: {stall: hold}",
        ],
    );
    refused(
        &text,
        (19, 17),
        "buses[0].joints[1].faults",
        &[
            "`gripper` is a wheel",
            "follows no path",
            "remove `faults:`",
        ],
    );
}
