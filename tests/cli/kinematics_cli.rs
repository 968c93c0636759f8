//! `servobus fk` and `servobus ik` on the shipped robots, and the robot
//! file's `kinematics:` section as the loader checks it. Expected figures
//! are worked out by hand from the geometry in configs/robots/so101.yaml
//! and hexapod.yaml (see their comments).

use crate::common;

use common::{arg, edited, exited, json, num, says, servobus, servobus_json, temp_file};

fn xyz(v: &serde_json::Value) -> [f64; 3] {
    let a = v["xyz"].as_array().expect("xyz");
    [0, 1, 2].map(|i| a[i].as_f64().expect("a number"))
}

/// `servobus ik` placing `frame` of `robot` at `xyz`, with `more` arguments.
fn ik(robot: &str, frame: &str, xyz: &str, more: &[&str]) -> std::process::Output {
    let args = ["ik", "--robot", robot, "--frame", frame, "--xyz", xyz];
    servobus(&[&args[..], more].concat())
}

/// [`ik`], which must succeed: its JSON.
fn ik_json(robot: &str, frame: &str, xyz: &str, more: &[&str]) -> serde_json::Value {
    let out = ik(robot, frame, xyz, more);
    exited(&out, 0);
    json(&out)
}

fn close(got: [f64; 3], want: [f64; 3], tol: f64) {
    let d = (0..3)
        .map(|i| (got[i] - want[i]).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(d < tol, "{got:?} is {d} from {want:?}");
}

#[test]
fn fk_json_gives_every_joint_frame_and_named_frame() {
    let v = servobus_json(&["fk", "--robot", "so101", "--json"]);
    let frames = v["frames"].as_object().expect("frames");
    let mut names: Vec<&str> = frames.keys().map(String::as_str).collect();
    names.sort_unstable();
    assert_eq!(
        names,
        [
            "elbow_flex",
            "gripper",
            "shoulder_lift",
            "shoulder_pan",
            "tool",
            "wrist_flex",
            "wrist_roll"
        ]
    );
    // The calibration pose: 30.4 + 28 + 134.9 + 61.1 + 98.13 forward,
    // 18.28 right then 18.1 + 0.17 left, 64.8 + 54.2 + 112.57 + 5.2 up and
    // 7.9 down; turned as the tool is on the roll joint, every joint
    // frame being level.
    close(xyz(&frames["tool"]), [352.53, -0.01, 228.87], 1e-6);
    let rpy = frames["tool"]["rpy"].as_array().expect("rpy");
    let rpy = [0, 1, 2].map(|i| rpy[i].as_f64().expect("a number"));
    close(rpy, [2.789, -0.001, 0.001], 1e-6);
}

#[test]
fn fk_pose_is_in_the_robot_file_s_units() {
    let v = servobus_json(&[
        "fk",
        "--robot",
        "so101",
        "--pose",
        "{shoulder_pan: 90, elbow_flex: 90}",
        "--json",
    ]);
    // Elbow down: the tool 5.2 - 7.9 beyond the elbow (58.4) and 134.9 +
    // 159.23 below it (231.57), 0.01 right of the pan axis, all turned to
    // the left; pointing down but for the tool's own 0.001 deg of pitch
    // and yaw on the roll joint (0.0014 deg together).
    close(xyz(&v["frames"]["tool"]), [0.01, 55.7, -62.56], 1e-6);
    let rpy = v["frames"]["tool"]["rpy"].as_array().expect("rpy");
    assert!(
        (rpy[1].as_f64().expect("pitch") - 90.0).abs() < 0.002,
        "{rpy:?}"
    );
}

#[test]
fn ik_answers_put_the_tool_where_asked() {
    let v = ik_json(
        "so101",
        "tool",
        "250,50,120",
        &["--pitch", "30", "--roll", "10", "--json"],
    );
    let joints = v["joints"].as_object().expect("joints");
    let pose: Vec<String> = joints.iter().map(|(k, a)| format!("{k}: {a}")).collect();
    let pose = format!("{{{}}}", pose.join(", "));
    let f = servobus_json(&["fk", "--robot", "so101", "--pose", &pose, "--json"]);
    close(xyz(&f["frames"]["tool"]), [250.0, 50.0, 120.0], 0.01);
    let rpy = f["frames"]["tool"]["rpy"].as_array().expect("rpy");
    let (roll, pitch) = (rpy[0].as_f64().expect("r"), rpy[1].as_f64().expect("p"));
    assert!(
        (pitch - 30.0).abs() < 0.01 && (roll - 10.0).abs() < 0.01,
        "{rpy:?}"
    );
}

#[test]
fn ik_prints_the_robot_s_joint_order_in_a_form_fk_pose_takes() {
    let out = ik("so101", "tool", "250,50,120", &["--pitch", "30"]);
    let (text, _) = exited(&out, 0);
    let names: Vec<&str> = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .filter_map(|l| l.split(':').next())
        .collect();
    // The robot file's order (the arm's chain; the gripper is not in it).
    let order = [
        "shoulder_pan",
        "shoulder_lift",
        "elbow_flex",
        "wrist_flex",
        "wrist_roll",
    ];
    assert_eq!(names, order, "{text}");
    // The text as it is, given to fk: the tool is back where ik put it.
    let f = servobus_json(&["fk", "--robot", "so101", "--pose", &text, "--json"]);
    close(xyz(&f["frames"]["tool"]), [250.0, 50.0, 120.0], 0.05);
    let rpy = f["frames"]["tool"]["rpy"].as_array().expect("rpy");
    let pitch = rpy[1].as_f64().expect("pitch");
    assert!((pitch - 30.0).abs() < 0.01, "{rpy:?}");
    // The JSON's keys come in the same order.
    let out = ik("so101", "tool", "250,50,120", &["--pitch", "30", "--json"]);
    let (line, _) = exited(&out, 0);
    let at: Vec<usize> = order
        .iter()
        .map(|j| line.find(&format!("\"{j}\"")).unwrap_or(usize::MAX))
        .collect();
    assert!(at.windows(2).all(|w| w[0] < w[1]), "{line}");
}

#[test]
fn ik_places_a_hexapod_foot_with_negative_coordinates() {
    // Middle right hip at (0, -90, 0); 200 out and 40 down from it.
    let v = ik_json("hexapod", "foot_middle_right", "0,-290,-40", &["--json"]);
    let j = &v["joints"];
    assert!(num(j, "middle_right_coxa").abs() < 1e-9, "{j}");
    let pose = format!(
        "{{middle_right_femur: {}, middle_right_tibia: {}}}",
        num(j, "middle_right_femur"),
        num(j, "middle_right_tibia")
    );
    let f = servobus_json(&["fk", "--robot", "hexapod", "--pose", &pose, "--json"]);
    close(
        xyz(&f["frames"]["foot_middle_right"]),
        [0.0, -290.0, -40.0],
        0.01,
    );
}

#[test]
fn ik_out_of_reach_exits_1_with_the_distance_short() {
    // Straight ahead at the lift axis's height (119.0): 569.6 from it,
    // the arm reaches 116.0 + 135.0 + 159.43 (the tool 159.23 beyond the
    // wrist flex axis and 7.9 below the roll axis) = 410.43.
    let out = ik("so101", "tool", "600,0,119", &["--json"]);
    let (_, _) = exited(&out, 1);
    let v = json(&out);
    assert!((num(&v, "short_mm") - 159.17).abs() < 0.5, "{v}");
    let text = ik("so101", "tool", "600,0,119", &[]);
    let (o, _) = exited(&text, 1);
    says(&o, &["unreachable", "159.17"]);
}

#[test]
fn ik_beyond_a_limit_names_the_joint() {
    // The tool where it is at zero, rolled 170 deg: it sits rolled 2.789
    // deg on the roll joint, so wrist_roll (its axis points back) would go
    // to -167.2; its limits are +-160.
    let out = ik(
        "so101",
        "tool",
        "352.53,-0.01,228.87",
        &["--pitch", "0", "--roll", "170", "--json"],
    );
    exited(&out, 1);
    assert_eq!(json(&out)["joint"], "wrist_roll");
}

#[test]
fn bad_input_exits_2() {
    for args in [
        &[
            "ik", "--robot", "so101", "--frame", "nose", "--xyz", "1,2,3",
        ][..],
        &["ik", "--robot", "so101", "--frame", "tool", "--xyz", "1,2"],
        &[
            "ik", "--robot", "so101", "--frame", "tool", "--xyz", "1,x,2",
        ],
        &["fk", "--robot", "so101", "--pose", "{elbow: 3}"],
        &["fk", "--robot", "so101", "--pose", "[1, 2]"],
        &["fk", "--robot", "scs-mini"],
    ] {
        let out = servobus(args);
        exited(&out, 2);
    }
}

#[test]
fn a_geometry_problem_is_reported_at_its_place_in_the_file() {
    let text = edited(
        "configs/robots/so101.yaml",
        &[(
            "elbow_flex: {parent: shoulder_lift,",
            "elbow_flex: {parent: shoulder,",
        )],
    );
    let line = text
        .lines()
        .position(|l| l.contains("elbow_flex: {parent: shoulder,"))
        .expect("the edited line")
        + 1;
    let robot = temp_file("kinematics_cli", "bad_parent.yaml", &text);
    let out = servobus(&["fk", "--robot", arg(&robot)]);
    let (_, e) = exited(&out, 2);
    says(
        &e,
        &[
            &format!(":{line}:"),
            "kinematics.joints.elbow_flex.parent",
            "unknown parent `shoulder`",
        ],
    );
}

#[test]
fn every_robot_joint_needs_geometry() {
    let text = edited(
        "configs/robots/so101.yaml",
        &[("    gripper: {parent: wrist_roll, xyz: [23.4, 17.79, 21.09], rpy: [0, 0, 0], axis: [0, -0.998815, -0.048663]}\n", "")],
    );
    let robot = temp_file("kinematics_cli", "no_gripper.yaml", &text);
    let out = servobus(&["fk", "--robot", arg(&robot)]);
    let (_, e) = exited(&out, 2);
    says(
        &e,
        &["kinematics.joints", "joint `gripper` has no geometry"],
    );
}

#[test]
fn geometry_for_a_joint_the_robot_lacks_is_refused() {
    let text = edited(
        "configs/robots/so101.yaml",
        &[(
            "  frames:\n",
            "    elbow2: {parent: base, xyz: [0, 0, 0], axis: [0, 0, 1]}\n  frames:\n",
        )],
    );
    let robot = temp_file("kinematics_cli", "extra_joint.yaml", &text);
    let out = servobus(&["fk", "--robot", arg(&robot)]);
    let (_, e) = exited(&out, 2);
    says(&e, &["kinematics.joints.elbow2", "no joint `elbow2`"]);
}

#[test]
fn the_two_hexapods_share_one_geometry() {
    let a = servobus_json(&[
        "fk",
        "--robot",
        "hexapod",
        "--pose",
        "{front_left_femur: 30}",
        "--json",
    ]);
    let b = servobus_json(&[
        "fk",
        "--robot",
        "hexapod-2bus",
        "--pose",
        "{front_left_femur: 30}",
        "--json",
    ]);
    assert_eq!(a, b);
}

/// A motion for the SO-101: home, a tool keyframe (gripper opened in the
/// same keyframe), a joint keyframe, and `last` as the last keyframe.
fn arm_motion(name: &str, last: &str) -> std::path::PathBuf {
    let text = format!(
        "units: deg\nkeyframes:\n  - pose: {{shoulder_lift: -90, elbow_flex: 90}}\n  - tool: {{xyz: [250, 50, 120], pitch: 30, roll: 0}}\n    pose: {{gripper: 40}}\n  - pose: {{shoulder_pan: 10}}\n  - {last}\n"
    );
    temp_file("kinematics_cli", name, &text)
}

#[test]
fn tool_keyframes_become_joint_keyframes_at_load() {
    let motion = arm_motion("tool.yaml", "tool: {xyz: [200, -80, 60], pitch: 60}");
    let robot = common::repo("configs/robots/so101.yaml");
    let (m, r) = servobus_runtime::config::load_motion(&motion, Some(&robot)).expect("loads");
    let model = r.geometry().expect("geometry");
    let tool = model.frame_index("tool").expect("tool");
    let mut poses = servobus_kinematics::Poses::new(&model);
    for (k, want) in [(1, [250.0, 50.0, 120.0]), (3, [200.0, -80.0, 60.0])] {
        let q: Vec<f64> = m.keyframes[k]
            .positions
            .iter()
            .map(|d| d.to_radians())
            .collect();
        model.forward(&q, &mut poses);
        let at = poses.frame(tool).expect("tool").translation.vector;
        close([at.x, at.y, at.z], want, 0.01);
    }
    let gripper = r.joint_index("gripper").expect("gripper");
    assert_eq!(m.keyframes[1].positions[gripper], 40.0);
    let plan = servobus(&["plan", arg(&motion), "--robot", "so101", "--json"]);
    exited(&plan, 0);
}

#[test]
fn an_unreachable_tool_keyframe_is_refused_at_its_line() {
    // As `ik` out of reach: 159.17 short.
    let motion = arm_motion("far.yaml", "tool: {xyz: [600, 0, 119]}");
    let out = servobus(&["plan", arg(&motion), "--robot", "so101"]);
    let (_, e) = exited(&out, 2);
    says(&e, &[":7:", "keyframes[3].tool", "unreachable", "159.17"]);
}
