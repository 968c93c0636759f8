//! Every robot and motion file shipped in `configs/` loads and validates.

use std::path::{Path, PathBuf};

use servobus_config::{load_motion, load_robot, plan_motion, RobotOptions, Units};

fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs")
}

fn yaml_files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("configs directory exists")
        .map(|e| e.expect("readable entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
        .collect();
    v.sort();
    v
}

/// The shipped files of `kind` (`robots`, `motions`), at least `expected`
/// of them, each with its text read as plain YAML: what the file says,
/// independently of the loader under test.
fn shipped(kind: &str, expected: usize) -> Vec<(PathBuf, serde_yaml::Value)> {
    let files = yaml_files(&configs().join(kind));
    assert!(
        files.len() >= expected,
        "expected {expected} {kind}, found {files:?}"
    );
    files
        .into_iter()
        .map(|f| {
            let text = std::fs::read_to_string(&f).expect("readable");
            let raw = serde_yaml::from_str(&text).expect("YAML");
            (f, raw)
        })
        .collect()
}

#[test]
fn every_robot_file_validates() {
    for (f, raw) in shipped("robots", 4) {
        let robot = load_robot(&f, &RobotOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        // The loader must keep every bus, joint, ID and limit as written
        // (all in degrees).
        assert_eq!(robot.name, raw["name"].as_str().expect("name"));
        assert_eq!(robot.units, Units::Deg, "{}", f.display());
        let buses = raw["buses"].as_sequence().expect("buses");
        assert_eq!(robot.buses.len(), buses.len(), "{}", f.display());
        for (bus, rb) in robot.buses.iter().zip(buses) {
            assert_eq!(bus.name, rb["name"].as_str().expect("bus name"));
            let baud = rb["baud"].as_u64().unwrap_or(1_000_000);
            assert_eq!(u64::from(bus.baud), baud, "{}", f.display());
            let joints = rb["joints"].as_sequence().expect("joints");
            assert!(!joints.is_empty(), "{}", f.display());
            assert_eq!(bus.joints.len(), joints.len(), "{}", f.display());
            for (j, rj) in bus.joints.iter().zip(joints) {
                let num = |k: &str| rj[k].as_f64().unwrap_or_else(|| panic!("{k} of {rj:?}"));
                assert_eq!(j.name, rj["name"].as_str().expect("joint name"));
                assert_eq!(Some(u64::from(j.id)), rj["id"].as_u64(), "{}", j.name);
                if rj["mode"].as_str() == Some("wheel") {
                    // A wheel has no position limits: both are 0.
                    assert!(j.is_wheel(), "{}", j.name);
                    assert_eq!((j.min, j.max), (0.0, 0.0), "{}", j.name);
                } else {
                    assert_eq!((j.min, j.max), (num("min"), num("max")), "{}", j.name);
                }
                assert_eq!(j.max_velocity, num("max_velocity"), "{}", j.name);
                assert_eq!(j.max_acceleration, num("max_acceleration"), "{}", j.name);
                assert_eq!(j.max_jerk, rj["max_jerk"].as_f64(), "{}", j.name);
            }
        }
    }
}

#[test]
fn every_motion_file_validates_against_its_robot() {
    for (f, raw) in shipped("motions", 5) {
        let (motion, robot) = load_motion(&f, None).unwrap_or_else(|e| panic!("{e}"));
        let written = raw["keyframes"].as_sequence().expect("keyframes").len();
        assert!(written >= 2, "{}", f.display());
        // A keyframe in space (a tool line, a walk, a body move) becomes
        // samples that share its place in the file: count the places.
        let mut places: Vec<(usize, usize)> = motion
            .keyframes
            .iter()
            .map(|k| (k.line, k.column))
            .collect();
        places.dedup();
        assert_eq!(places.len(), written, "{}", f.display());
        // Every shipped motion plans within its robot's limits.
        let traj = plan_motion(&motion, &robot).unwrap_or_else(|e| panic!("{e}"));
        assert!(traj.duration() > 0.0, "{}", f.display());
        assert_eq!(traj.joints(), robot.joint_count());
        for k in &motion.keyframes {
            assert_eq!(k.positions.len(), robot.joint_count());
            for (p, j) in k.positions.iter().zip(robot.joints()) {
                let v = motion.units.convert(*p, robot.units);
                assert!(
                    v >= j.min && v <= j.max,
                    "{}: {} at {v}",
                    f.display(),
                    j.name
                );
            }
        }
    }
}

#[test]
fn shipped_robots_have_the_documented_shape() {
    let so101 = load_robot(
        &configs().join("robots/so101.yaml"),
        &RobotOptions::default(),
    )
    .expect("so101 loads");
    assert_eq!(so101.units, Units::Deg);
    assert_eq!(so101.buses.len(), 1);
    let ids: Vec<u8> = so101.joints().map(|j| j.id).collect();
    assert_eq!(ids, [1, 2, 3, 4, 5, 6]);
    assert!(so101.joints().all(|j| j.model.name == "STS3215"));
    assert_eq!(so101.buses[0].baud, 1_000_000);

    let hex = load_robot(
        &configs().join("robots/hexapod.yaml"),
        &RobotOptions::default(),
    )
    .expect("hexapod loads");
    assert_eq!((hex.buses.len(), hex.joint_count()), (1, 18));
    let hex2 = load_robot(
        &configs().join("robots/hexapod-2bus.yaml"),
        &RobotOptions::default(),
    )
    .expect("2-bus loads");
    assert_eq!(hex2.buses.len(), 2);
    assert_eq!(hex2.joint_count(), 18);
    let names: Vec<&str> = hex.joints().map(|j| j.name.as_str()).collect();
    let names2: Vec<&str> = hex2.joints().map(|j| j.name.as_str()).collect();
    assert_eq!(names, names2, "the two hexapods have the same joints");

    let scs = load_robot(
        &configs().join("robots/scs-mini.yaml"),
        &RobotOptions::default(),
    )
    .expect("scs-mini loads");
    assert!(scs.joints().all(|j| !j.model.series.has_sync_read()));
}
