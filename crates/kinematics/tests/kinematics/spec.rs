//! A geometry is checked into a tree with typed errors naming the entry.

use servobus_kinematics::{Geometry, Section, Spec, SpecError};

fn check(yaml: &str, joints: &[&str]) -> Result<Geometry, SpecError> {
    let spec: Spec = serde_yaml::from_str(yaml).expect("the spec's shape");
    Geometry::new(&spec, joints.iter().copied(), 1.0)
}

const TWO: &[&str] = &["a", "b"];

#[test]
fn an_unknown_parent_is_named() {
    let e = check(
        "joints:\n  a: {parent: base, xyz: [0,0,0], axis: [0,0,1]}\n  b: {parent: c, xyz: [0,0,0], axis: [0,0,1]}\n",
        TWO,
    )
    .unwrap_err();
    assert!(matches!(&e, SpecError::UnknownParent { parent, .. } if parent == "c"));
    assert_eq!(e.location(), (Section::Joints, Some("b"), Some("parent")));
}

#[test]
fn a_cycle_is_refused() {
    let e = check(
        "joints:\n  a: {parent: b, xyz: [0,0,0], axis: [0,0,1]}\n  b: {parent: a, xyz: [0,0,0], axis: [0,0,1]}\n",
        TWO,
    )
    .unwrap_err();
    assert!(matches!(e, SpecError::Cycle { .. }), "{e:?}");
}

#[test]
fn an_axis_not_of_unit_length_or_zero_is_refused() {
    for axis in ["[0,0,0]", "[0,0,2]", "[1,1,0]"] {
        let e = check(
            &format!("joints:\n  a: {{parent: base, xyz: [0,0,0], axis: {axis}}}\n"),
            &["a"],
        )
        .unwrap_err();
        assert!(matches!(e, SpecError::BadAxis { .. }), "{axis}: {e:?}");
        assert_eq!(e.location(), (Section::Joints, Some("a"), Some("axis")));
    }
}

#[test]
fn a_frame_without_a_parent_is_refused() {
    let e = check(
        "joints:\n  a: {parent: base, xyz: [0,0,0], axis: [0,0,1]}\nframes:\n  tool: {parent: '', xyz: [0,0,0]}\n",
        &["a"],
    )
    .unwrap_err();
    assert_eq!(
        e,
        SpecError::NoParent {
            frame: "tool".into()
        }
    );
}

#[test]
fn joints_must_match_the_robot() {
    let yaml = "joints:\n  a: {parent: base, xyz: [0,0,0], axis: [0,0,1]}\n";
    assert_eq!(
        check(yaml, TWO).unwrap_err(),
        SpecError::MissingJoint { joint: "b".into() }
    );
    assert_eq!(
        check(yaml, &[]).unwrap_err(),
        SpecError::UnknownJoint { joint: "a".into() }
    );
}

#[test]
fn rpy_is_converted_from_the_file_unit() {
    let spec: Spec = serde_yaml::from_str(
        "joints:\n  a: {parent: base, xyz: [0,0,0], rpy: [0, 0, 90], axis: [0,0,1]}\nframes:\n  f: {parent: a, xyz: [10,0,0]}\n",
    )
    .expect("shape");
    let model = Geometry::new(&spec, ["a"], 1f64.to_radians()).expect("valid");
    let mut p = servobus_kinematics::Poses::new(&model);
    model.forward(&[0.0], &mut p);
    let at = p.frame(0).expect("f").translation.vector;
    assert!(
        (at - servobus_kinematics::Vector3::new(0.0, 10.0, 0.0)).norm() < 1e-9,
        "{at:?}"
    );
}
