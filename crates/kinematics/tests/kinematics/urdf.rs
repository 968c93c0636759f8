//! URDF import: the SO-101's published URDF against the hand-typed
//! geometry of the shipped so101, IK on the imported chain, and broken
//! URDFs.

use std::path::{Path, PathBuf};

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use serde_yaml::Value;
use servobus_kinematics::{
    Geometry, Isometry3, Poses, Spec, Urdf, UrdfError, UrdfSpec, VisualGeometry, BASE,
};

use crate::ik_arm::round_trips_on;
use crate::robots::{shipped, Shipped};

const DEG: f64 = std::f64::consts::PI / 180.0;

fn testdata(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata/urdf")
        .join(rel)
}

fn yaml(rel: &str) -> Value {
    let text = std::fs::read_to_string(testdata(rel)).expect("test data");
    serde_yaml::from_str(&text).expect("valid YAML")
}

/// testdata/urdf/so101_urdf.yaml's `kinematics:` section.
fn so101_spec() -> UrdfSpec {
    serde_yaml::from_value(yaml("so101_urdf.yaml")["kinematics"].clone()).expect("a URDF section")
}

fn so101_urdf() -> Urdf {
    Urdf::load(&so101_spec(), &testdata(""), DEG).expect("the SO-101 URDF imports")
}

/// The robot file's joints, and the limits it gives (radians).
fn robot_joints() -> Vec<(String, Option<(f64, f64)>)> {
    let doc = yaml("so101_urdf.yaml");
    let joints = doc["buses"][0]["joints"].as_sequence().expect("joints");
    let lim = |j: &Value| Some((j["min"].as_f64()? * DEG, j["max"].as_f64()? * DEG));
    joints
        .iter()
        .map(|j| (j["name"].as_str().expect("name").to_owned(), lim(j)))
        .collect()
}

/// `spec` as a robot model with the robot file's limits, else the URDF's.
fn model(spec: &Spec, urdf: &Urdf) -> Shipped {
    let joints = robot_joints();
    let names: Vec<String> = joints.iter().map(|(n, _)| n.clone()).collect();
    let mut model =
        Geometry::new(spec, names.iter().map(String::as_str), DEG).expect("valid geometry");
    for (i, (name, own)) in joints.iter().enumerate() {
        let (lo, hi) = own.or(urdf.limits[name].position).expect("limits");
        model.set_limits(i, lo, hi);
    }
    Shipped { model, names }
}

/// The largest distance between the joint frames' origins and between the
/// `tool` frames of `a` and `b` (mm), and between the tools' orientations
/// (deg), over 1000 random poses inside `a`'s limits.
fn disagreement(a: &Geometry, b: &Geometry) -> (f64, f64, f64) {
    let mut rng = SmallRng::seed_from_u64(40);
    let (mut pa, mut pb) = (Poses::new(a), Poses::new(b));
    let (ta, tb) = (
        a.frame_index("tool").unwrap(),
        b.frame_index("tool").unwrap(),
    );
    let (mut joint, mut tool, mut turn) = (0.0f64, 0.0f64, 0.0f64);
    for _ in 0..1000 {
        let q: Vec<f64> = (0..a.joint_count())
            .map(|i| {
                let (lo, hi) = a.limits(i).unwrap();
                rng.gen_range(lo..=hi)
            })
            .collect();
        a.forward(&q, &mut pa);
        b.forward(&q, &mut pb);
        let dist = |x: &Isometry3<f64>, y: &Isometry3<f64>| {
            (x.translation.vector - y.translation.vector).norm()
        };
        for i in 0..a.joint_count() {
            let j = b.joint_index(a.joint_name(i).unwrap()).unwrap();
            joint = joint.max(dist(pa.joint(i).unwrap(), pb.joint(j).unwrap()));
        }
        let (x, y) = (pa.frame(ta).unwrap(), pb.frame(tb).unwrap());
        tool = tool.max(dist(x, y));
        turn = turn.max(x.rotation.angle_to(&y.rotation) / DEG);
    }
    (joint, tool, turn)
}

#[test]
fn the_so101_urdf_loads_with_its_limits_and_meshes() {
    let urdf = so101_urdf();
    assert_eq!(urdf.spec.joints.len(), 6);
    assert_eq!(urdf.spec.joints["shoulder_pan"].parent, BASE);
    assert_eq!(urdf.spec.joints["gripper"].parent, "wrist_roll");
    // gripper_frame_link hangs on the gripper link by a fixed joint.
    assert_eq!(urdf.spec.frames["tool"].parent, "wrist_roll");
    // Limits in servobus's angle: the pan inverted, the rest as written.
    let lim = |j: &str| urdf.limits[j].position.unwrap();
    assert_eq!(lim("shoulder_pan"), (-1.91986, 1.91986));
    assert_eq!(lim("elbow_flex"), (-1.69, 1.69));
    assert_eq!(lim("wrist_roll"), (-2.74385, 2.84121));
    assert_eq!(urdf.limits["gripper"].velocity, Some(10.0));
    assert_eq!(urdf.limits["elbow_flex"].urdf_joint, "elbow_flex");
    // Seven links draw 13 STL files (some more than once), all resolved
    // next to the URDF; the jaw rides on the gripper joint.
    assert_eq!(urdf.links.len(), 7);
    let meshes: Vec<&Path> = urdf
        .links
        .iter()
        .flat_map(|l| &l.visuals)
        .filter_map(|v| match &v.geometry {
            VisualGeometry::Mesh { path, .. } => Some(path.as_path()),
            _ => None,
        })
        .collect();
    assert_eq!(meshes.len(), 17);
    assert!(meshes
        .iter()
        .all(|p| p.is_file() && p.starts_with(testdata("so101/assets"))));
    let jaw = urdf
        .links
        .iter()
        .find(|l| l.link == "moving_jaw_so101_v1_link")
        .unwrap();
    assert_eq!(jaw.parent, "gripper");
    let base = urdf.links.iter().find(|l| l.link == "base_link").unwrap();
    assert_eq!(base.parent, BASE);
    assert!((base.origin.translation.vector.x + 38.8353).abs() < 1e-9);
}

#[test]
fn the_imported_zero_pose_is_where_the_urdf_puts_it() {
    // From the URDF by hand: the roll joint 293.23 forward, 0.18 right and
    // 234.37 up of base_link, the tool (gripper_frame_link) 98.13 further
    // and 7.9 down; base_link 38.84 behind and 2.4 above servobus's base.
    let urdf = so101_urdf();
    let s = model(&urdf.spec, &urdf);
    let mut poses = Poses::new(&s.model);
    s.model.forward(&[0.0; 6], &mut poses);
    let roll = poses
        .joint(s.model.joint_index("wrist_roll").unwrap())
        .unwrap();
    let tool = poses.frame(s.model.frame_index("tool").unwrap()).unwrap();
    let near = |p: &Isometry3<f64>, want: [f64; 3]| {
        let v = p.translation.vector;
        (v.x - want[0]).abs() < 0.01 && (v.y - want[1]).abs() < 0.01 && (v.z - want[2]).abs() < 0.01
    };
    assert!(near(roll, [254.39, -0.18, 236.77]), "{roll}");
    assert!(near(tool, [352.52, -0.01, 228.87]), "{tool}");
    // The tool's x runs along the gripper, forward.
    let x = tool.rotation * nalgebra::Vector3::x();
    assert!(x.x > 0.9999, "{x}");
}

#[test]
fn fk_agrees_with_the_shipped_so101_on_1000_poses() {
    // configs/robots/so101.yaml types the URDF's geometry by hand, to
    // 0.01 mm and 0.001 deg: measured, its joints and tool are within
    // 0.01 mm of the imported chain's, the tool turned within 0.003 deg.
    let urdf = so101_urdf();
    let imported = model(&urdf.spec, &urdf);
    let (joint, tool, turn) = disagreement(&imported.model, &shipped("so101").model);
    eprintln!("shipped so101: joints {joint:.4} mm, tool {tool:.4} mm, {turn:.4} deg");
    assert!(
        joint <= 0.5 && tool <= 0.5,
        "joints {joint} mm, tool {tool} mm"
    );
    assert!(turn < 0.05, "tool orientation {turn} deg");
}

#[test]
fn zero_and_inverted_turn_the_urdf_angle() {
    // The URDF angle is zero + angle (zero - angle when inverted): FK of
    // the mapped chain at q equals FK of the plain chain at the URDF angle.
    let plain = so101_urdf();
    let mut spec = so101_spec();
    spec.zero.insert("elbow_flex".into(), 30.0);
    spec.zero.insert("shoulder_pan".into(), -20.0);
    spec.inverted.push("wrist_flex".into());
    let turned = Urdf::load(&spec, &testdata(""), DEG).expect("imports");
    let a = model(&plain.spec, &plain);
    let b = model(&turned.spec, &plain);
    let (mut pa, mut pb) = (Poses::new(&a.model), Poses::new(&b.model));
    let mut rng = SmallRng::seed_from_u64(7);
    for _ in 0..200 {
        let q: Vec<f64> = (0..6).map(|_| rng.gen_range(-1.5..1.5)).collect();
        let mut urdf_q = q.clone();
        // Pan is inverted in both: URDF angle -20 - q here, -(q + 20) there.
        urdf_q[0] = q[0] + 20.0 * DEG;
        urdf_q[2] = q[2] + 30.0 * DEG;
        urdf_q[3] = -q[3];
        b.model.forward(&q, &mut pb);
        a.model.forward(&urdf_q, &mut pa);
        let tool = |p: &Poses, s: &Shipped| *p.frame(s.model.frame_index("tool").unwrap()).unwrap();
        let miss = (tool(&pa, &a).translation.vector - tool(&pb, &b).translation.vector).norm();
        assert!(miss < 1e-9, "{miss} mm at {q:?}");
    }
    // The limits move with the zero and flip with the direction.
    let (lo, hi) = turned.limits["elbow_flex"].position.unwrap();
    assert!((lo + 1.69 + 30.0 * DEG).abs() < 1e-12 && (hi - 1.69 + 30.0 * DEG).abs() < 1e-12);
}

#[test]
fn ik_round_trips_10000_random_poses_on_the_imported_chain() {
    // As the shipped chain's test: from a previous solution within 10 deg.
    let urdf = so101_urdf();
    let s = model(&urdf.spec, &urdf);
    let refused = round_trips_on(&s, |rng, q| {
        q.iter()
            .map(|v| v + rng.gen_range(-10f64..10.0).to_radians())
            .collect()
    });
    eprintln!("imported chain, refused from nearby: {refused} of 10000");
    assert!(refused <= 5, "{refused} of 10000 refused");
}

#[test]
fn ik_round_trips_10000_random_poses_from_home_on_the_imported_chain() {
    // From so101's home (lift -90, elbow 90, wrist 45), restarting from
    // spread-out poses where home leads nowhere: at most 0.1 % refused.
    let urdf = so101_urdf();
    let s = model(&urdf.spec, &urdf);
    let home: Vec<f64> = [0.0, -90.0, 90.0, 45.0, 0.0].map(|d: f64| d * DEG).to_vec();
    let refused = round_trips_on(&s, |_, _| home.clone());
    eprintln!("imported chain, refused from home: {refused} of 10000");
    assert!(refused <= 10, "{refused} of 10000 refused");
}

/// Imports `testdata/urdf/broken/<name>` with the two joints mapped.
fn broken(name: &str) -> (UrdfError, String) {
    let spec: UrdfSpec = serde_yaml::from_str(&format!(
        "{{urdf: broken/{name}, joints: {{shoulder: shoulder, elbow: elbow}}}}"
    ))
    .unwrap();
    let err = Urdf::load(&spec, &testdata(""), DEG).expect_err("refused");
    let text = err.to_string();
    eprintln!("{text}");
    (err, text)
}

/// The 1-based line of `broken/<name>` that holds `what`.
fn line_of(name: &str, what: &str) -> usize {
    let text = std::fs::read_to_string(testdata("broken").join(name)).unwrap();
    text.lines().position(|l| l.contains(what)).unwrap() + 1
}

#[test]
fn a_missing_joint_is_named_with_those_the_file_has() {
    let (err, text) = broken("missing_joint.urdf");
    assert!(matches!(err, UrdfError::MissingJoint { .. }), "{err:?}");
    assert!(
        text.contains("broken/missing_joint.urdf: no joint `elbow`"),
        "{text}"
    );
    assert!(text.contains("shoulder (revolute)"), "{text}");
}

#[test]
fn a_loop_is_refused_at_a_joint_on_it() {
    let (err, text) = broken("loop.urdf");
    let UrdfError::Loop { place, .. } = &err else {
        panic!("{err:?}")
    };
    let lines = [
        line_of("loop.urdf", "name=\"shoulder\""),
        line_of("loop.urdf", "name=\"elbow\""),
        line_of("loop.urdf", "name=\"closing\""),
    ];
    assert!(lines.contains(&(place.line.unwrap() as usize)), "{text}");
    assert!(
        text.contains("loop.urdf:") && text.contains("kinematic loop"),
        "{text}"
    );
}

#[test]
fn a_prismatic_joint_is_refused_at_its_line() {
    let (err, text) = broken("prismatic.urdf");
    assert!(matches!(err, UrdfError::Undrivable { .. }), "{err:?}");
    let line = line_of("prismatic.urdf", "type=\"prismatic\"");
    assert!(
        text.contains(&format!("prismatic.urdf:{line}: joint `elbow`")),
        "{text}"
    );
    assert!(text.contains("is prismatic"), "{text}");
}

#[test]
fn a_package_mesh_is_refused_with_a_hint() {
    let (err, text) = broken("package_mesh.urdf");
    assert!(matches!(err, UrdfError::PackageUri { .. }), "{err:?}");
    let line = line_of("package_mesh.urdf", "package://");
    assert!(
        text.contains(&format!("package_mesh.urdf:{line}: mesh `package://")),
        "{text}"
    );
    assert!(text.contains("relative to the URDF"), "{text}");
}

#[test]
fn malformed_xml_is_refused_at_its_line_and_column() {
    let (err, text) = broken("malformed.urdf");
    let UrdfError::Xml { place, column, .. } = &err else {
        panic!("{err:?}")
    };
    // The unclosed <child> is found where its parent's end tag is.
    let line = line_of("malformed.urdf", "</joint>");
    assert_eq!(place.line, Some(line as u32), "{text}");
    assert!(
        *column > 1 && text.contains("not well-formed XML"),
        "{text}"
    );
}

/// Imports `body` (inside <robot>) with `map` as the joints.
fn inline(body: &str, map: &str) -> String {
    let text = format!("<robot name=\"t\">\n{body}\n</robot>\n");
    let spec: UrdfSpec = serde_yaml::from_str(&format!("{{urdf: t.urdf, {map}}}")).unwrap();
    let err = Urdf::from_text(&text, Path::new("t.urdf"), &spec, DEG).expect_err("refused");
    err.to_string()
}

const LINKS: &str = "<link name=\"a\"/><link name=\"b\"/><link name=\"c\"/>";

#[test]
fn other_refusals_name_the_place() {
    let j = |name: &str, kind: &str, parent: &str, child: &str| {
        format!("<joint name=\"{name}\" type=\"{kind}\"><parent link=\"{parent}\"/><child link=\"{child}\"/></joint>")
    };
    let two_parents = format!(
        "{LINKS}\n{}\n{}",
        j("p", "revolute", "a", "c"),
        j("q", "revolute", "b", "c")
    );
    let text = inline(&two_parents, "joints: {p: p}");
    assert!(
        text.starts_with("t.urdf:4: link `c` has two parents, joint `p` (line 3)"),
        "{text}"
    );
    let fixed = format!(
        "{LINKS}\n{}\n{}",
        j("p", "fixed", "a", "b"),
        j("q", "revolute", "b", "c")
    );
    let text = inline(&fixed, "joints: {p: p}");
    assert!(
        text.starts_with("t.urdf:3: joint `p` (mapped from `p`) is fixed"),
        "{text}"
    );
    // q moves but is not mapped: r's chain to the base goes through it.
    let between = format!(
        "{LINKS}<link name=\"d\"/>\n{}\n{}\n{}",
        j("p", "revolute", "a", "b"),
        j("q", "continuous", "b", "c"),
        j("r", "revolute", "c", "d")
    );
    let text = inline(&between, "joints: {p: p, r: r}");
    assert!(
        text.starts_with("t.urdf:4: `r` does not reach its parent"),
        "{text}"
    );
    let text = inline(&fixed, "joints: {q: q}, frames: {tool: {link: e}}");
    assert!(text.contains("no link `e` (for frame `tool`)"), "{text}");
    let text = inline(&fixed, "joints: {q: q}, zero: {p: 10}");
    assert!(text.contains("`zero` names `p`"), "{text}");
    let text = inline(
        "<link name=\"a\"><visual><geometry><box size=\"1 x 1\"/></geometry></visual></link>",
        "joints: {}",
    );
    assert!(
        text.starts_with("t.urdf:2: <box size=\"1 x 1\">: expected 3 finite numbers"),
        "{text}"
    );
    let text = inline("<link name=\"a\"><visual>\n<geometry><mesh filename=\"none.stl\"/></geometry></visual></link>", "joints: {}");
    assert!(
        text.starts_with("t.urdf:3: mesh `none.stl` not found"),
        "{text}"
    );
}
