//! `kinematics: {urdf: ...}`: the SO-101's URDF behind a robot file, its
//! limits, and refusals placed in both files.

use std::path::{Path, PathBuf};

use servobus_kinematics::{Poses, Vector3};

use super::*;
use crate::ConfigError;

fn testdata(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata/urdf")
        .join(rel)
}

fn so101_text() -> String {
    std::fs::read_to_string(testdata("so101_urdf.yaml")).expect("test data")
}

/// so101_urdf.yaml with its URDF named by absolute path and each
/// `(from, to)` replaced once, loaded as a text.
fn edited(edits: &[(&str, &str)]) -> Result<Robot, ConfigError> {
    let urdf = testdata("so101/so101_new_calib.urdf");
    let mut text = so101_text().replacen(
        "urdf: so101/so101_new_calib.urdf",
        &format!("urdf: {}", urdf.display()),
        1,
    );
    for (from, to) in edits {
        assert!(text.contains(from), "{from}");
        text = text.replacen(from, to, 1);
    }
    let source = RobotSource::Text {
        name: Path::new("so101_urdf.yaml"),
        text: &text,
    };
    load_robot(source, &RobotOptions::default())
}

/// The field and reason of an error about content.
fn refusal(r: Result<Robot, ConfigError>) -> (String, String) {
    let e = r.expect_err("refused");
    let text = e.to_string();
    eprintln!("{text}");
    (e.field().expect("about content").to_owned(), text)
}

#[test]
fn the_so101_robot_file_takes_its_geometry_and_limits_from_the_urdf() {
    let robot = load_robot(&testdata("so101_urdf.yaml"), &RobotOptions::default())
        .expect("the robot file loads, its URDF relative to it");
    let elbow = robot.joint("elbow_flex").expect("elbow");
    assert!(
        (elbow.max - 1.69f64.to_degrees()).abs() < 1e-9,
        "{}",
        elbow.max
    );
    assert!((elbow.min + 1.69f64.to_degrees()).abs() < 1e-9);
    let roll = robot.joint("wrist_roll").expect("roll");
    assert!((roll.min - (-2.74385f64).to_degrees()).abs() < 1e-9);
    // The gripper keeps the file's own limits, inside the URDF's.
    let gripper = robot.joint("gripper").expect("gripper");
    assert_eq!((gripper.min, gripper.max), (0.0, 100.0));
    // The tool at the zero pose: where the URDF's gripper_frame_link is,
    // x along the gripper.
    let model = robot.geometry().expect("geometry");
    let mut poses = Poses::new(&model);
    model.forward(&[0.0; 6], &mut poses);
    let tool = poses
        .frame(model.frame_index("tool").expect("tool"))
        .expect("pose");
    let want = Vector3::new(352.52, -0.01, 228.87);
    assert!((tool.translation.vector - want).norm() < 0.01, "{tool}");
    assert!((tool.rotation * Vector3::x()).x > 0.9999);
}

/// so101_urdf.yaml with the hand-typed `kinematics:` block of the shipped
/// configs/robots/so101.yaml instead of its URDF section.
fn hand_typed_text() -> String {
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/robots/so101.yaml");
    let shipped = std::fs::read_to_string(shipped).unwrap();
    let block = &shipped[shipped.find("\nkinematics:").unwrap() + 1..];
    let block = &block[..block.find("\nbuses:").unwrap() + 1];
    let text = so101_text();
    let (start, end) = (
        text.find("\nkinematics:").unwrap() + 1,
        text.find("\nbuses:").unwrap() + 1,
    );
    text.replace(&text[start..end], block)
}

#[test]
fn the_urdf_geometry_is_the_shipped_hand_typed_one() {
    // Typed by hand, a joint's limits are not taken from anywhere.
    let source = RobotSource::Text {
        name: Path::new("hand_typed.yaml"),
        text: &hand_typed_text(),
    };
    let (field, reason) = refusal(load_robot(source, &RobotOptions::default()));
    assert_eq!(field, "buses[0].joints[0]");
    assert!(reason.contains("missing field `min`"), "{reason}");
    // With the limits the URDF gave, the same geometry.
    let urdf = edited(&[]).expect("loads");
    let mut text = hand_typed_text();
    for j in urdf.joints().filter(|j| j.name != "gripper") {
        let at = text.find(&format!("{{name: {},", j.name)).unwrap() + 1;
        text.insert_str(at, &format!("min: {}, max: {}, ", j.min, j.max));
    }
    let source = RobotSource::Text {
        name: Path::new("hand_typed.yaml"),
        text: &text,
    };
    let hand = load_robot(source, &RobotOptions::default()).expect("loads");
    let (a, b) = (urdf.geometry().unwrap(), hand.geometry().unwrap());
    assert_eq!(a.limits(4), b.limits(4));
    let (mut pa, mut pb) = (Poses::new(&a), Poses::new(&b));
    let q = [0.3, -0.5, 0.8, 0.4, 1.0, 0.5];
    a.forward(&q, &mut pa);
    b.forward(&q, &mut pb);
    for i in 0..6 {
        let d = pa.joint(i).unwrap().translation.vector - pb.joint(i).unwrap().translation.vector;
        assert!(d.norm() < 0.05, "joint {i}: {d}");
    }
}

#[test]
fn a_limit_beyond_the_urdf_is_refused_naming_both() {
    let (field, reason) = refusal(edited(&[(
        "{name: wrist_roll, id: 5,",
        "{name: wrist_roll, id: 5, min: -160, max: 160,",
    )]));
    assert_eq!(field, "buses[0].joints[4].min");
    assert!(
        reason.contains("min -160 deg is below the URDF's lower limit -157.21 deg"),
        "{reason}"
    );
    assert!(reason.contains("so101_new_calib.urdf:"), "{reason}");
    // Within the URDF's rounding (1.91986 rad for 110 deg) passes.
    let r = edited(&[(
        "{name: shoulder_pan, id: 1,",
        "{name: shoulder_pan, id: 1, min: -110, max: 110,",
    )]);
    assert!(r.is_ok(), "{r:?}");
}

#[test]
fn a_missing_urdf_joint_is_reported_at_its_entry_and_lists_the_file_s() {
    let (field, reason) = refusal(edited(&[("elbow_flex: elbow_flex", "elbow_flex: elbow")]));
    assert_eq!(field, "kinematics.joints.elbow_flex");
    assert!(reason.starts_with("so101_urdf.yaml:14:"), "{reason}");
    assert!(
        reason.contains("no joint `elbow` (mapped from `elbow_flex`)"),
        "{reason}"
    );
    assert!(
        reason.contains("wrist_roll (revolute), wrist_flex (revolute)"),
        "{reason}"
    );
}

#[test]
fn a_broken_urdf_is_reported_at_the_urdf_key_with_its_own_line() {
    let prismatic = testdata("broken/prismatic.urdf");
    let text = format!(
        "name: t\nbuses:\n  - name: b\n    joints:\n      - {{name: shoulder, id: 1, model: sts3215, \
         max_velocity: 90, max_acceleration: 90}}\n      - {{name: elbow, id: 2, model: sts3215, \
         max_velocity: 90, max_acceleration: 90}}\nkinematics:\n  urdf: {}\n  joints: {{shoulder: \
         shoulder, elbow: elbow}}\n",
        prismatic.display()
    );
    let source = RobotSource::Text {
        name: Path::new("t.yaml"),
        text: &text,
    };
    let (field, reason) = refusal(load_robot(source, &RobotOptions::default()));
    assert_eq!(field, "kinematics.joints.elbow");
    assert!(
        reason.contains("prismatic.urdf:14: joint `elbow`"),
        "{reason}"
    );
    let (field, reason) = refusal(edited(&[("so101_new_calib.urdf     #", "none.urdf #")]));
    assert_eq!(field, "kinematics.urdf");
    assert!(
        reason.contains("none.urdf: cannot read: no such file"),
        "{reason}"
    );
}

#[test]
fn the_two_forms_do_not_mix() {
    let (field, reason) = refusal(edited(&[(
        "gripper: gripper",
        "gripper: {parent: wrist_roll, xyz: [0, 0, 0], axis: [0, 1, 0]}",
    )]));
    assert_eq!(field, "kinematics.joints.gripper");
    assert!(
        reason.contains("with `urdf:`, a joint is the name of its URDF joint"),
        "{reason}"
    );
    let (field, reason) = refusal(edited(&[(
        "tool: {link: gripper_frame_link, rpy: [0, -90, 0]}",
        "tool: {parent: wrist_roll, xyz: [0, 0, 0]}",
    )]));
    assert_eq!(field, "kinematics.frames.tool");
    assert!(reason.contains("a frame is on a URDF link"), "{reason}");
    // Without `urdf:`, the URDF form's keys and entries are refused.
    let tiny = |kinematics: &str| {
        let text = format!(
            "name: t\nbuses:\n  - name: b\n    joints:\n      - {{name: a, id: 1, model: sts3215, \
             min: -90, max: 90, max_velocity: 90, max_acceleration: 90}}\nkinematics:\n{kinematics}"
        );
        let source = RobotSource::Text {
            name: Path::new("t.yaml"),
            text: &text,
        };
        refusal(load_robot(source, &RobotOptions::default()))
    };
    let (field, reason) =
        tiny("  joints: {a: {parent: base, xyz: [0, 0, 0], axis: [0, 0, 1]}}\n  zero: {a: 10}\n");
    assert_eq!(field, "kinematics.zero");
    assert!(reason.contains("`zero:` needs `urdf: FILE`"), "{reason}");
    let (field, reason) = tiny("  joints: {a: a_joint}\n");
    assert_eq!(field, "kinematics.joints.a");
    assert!(
        reason.contains("a URDF joint's name (typed by hand"),
        "{reason}"
    );
    let (field, reason) = tiny("  joints: {a: {parent: base, xyz: [0, 0, 0], axis: [0, 0, 1]}}\n  frames: {tool: {xyz: [1, 0, 0]}}\n");
    assert_eq!(field, "kinematics.frames.tool");
    assert!(reason.contains("missing field `parent`"), "{reason}");
    let (field, reason) = refusal(edited(&[("zero: {}", "zero: {elbow: 3}")]));
    assert_eq!(field, "kinematics.zero.elbow");
    assert!(
        reason.contains("`zero` names `elbow`, which `joints` does not map"),
        "{reason}"
    );
}

#[test]
fn the_shipped_hand_typed_robots_still_load() {
    for name in ["so101", "hexapod"] {
        let r = load_robot(
            RobotSource::Builtin(name),
            &RobotOptions::default().any_rate(),
        );
        assert!(r.expect("loads").kinematics.is_some(), "{name}");
    }
}

#[test]
fn a_problem_inside_a_hand_typed_entry_keeps_its_place() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/robots/so101.yaml"),
    )
    .unwrap();
    let text = text.replacen(
        "rpy: [0, 0, 0], axis: [0, 1, 0]}",
        "rpy: [0, 0, 0], axs: [0, 1, 0]}",
        1,
    );
    let line = text.lines().position(|l| l.contains("axs:")).unwrap() + 1;
    let source = RobotSource::Text {
        name: Path::new("so101.yaml"),
        text: &text,
    };
    let e = load_robot(source, &RobotOptions::default()).expect_err("refused");
    eprintln!("{e}");
    assert_eq!(e.position().map(|p| p.0), Some(line), "{e}");
    assert!(e.to_string().contains("unknown field `axs`"), "{e}");
}
