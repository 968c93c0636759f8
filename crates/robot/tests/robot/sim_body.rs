//! The simulated robot's body through the facade's simulator glue
//! (`servobus_robot::sim`): mounting and hand files, random units, the
//! truth recorder, in virtual time.

use crate::common;

use std::time::Duration;

use servobus_protocol::registers::addr;
use servobus_robot::sim::{new_truth, Hand, Mounting, SimRobot};
use servobus_runtime::config::ConfigError;
use servobus_runtime::VirtualRun;
use servobus_trajectory::JointState;

/// Ticks per degree of an STS3215.
const TPD: f64 = 4096.0 / 360.0;

/// The raw tick of a mounting at `angle`, from the definition.
fn raw(zero: f64, dir: f64, angle: f64) -> i32 {
    ((zero + dir * angle * TPD).round() as i32).rem_euclid(4096)
}

/// How far apart two raw ticks are, the short way round the seam.
fn tick_diff(a: i32, b: i32) -> f64 {
    f64::from((a - b + 2048).rem_euclid(4096) - 2048)
}

#[test]
fn the_shipped_mounting_and_hand_read_back_raw_ticks_across_the_seam() {
    let robot = common::robot("so101.yaml");
    let mounting = Mounting::load(&common::config("sim/so101-mounting.yaml"), &robot)
        .expect("the shipped mounting loads");
    let hand =
        Hand::load(&common::config("sim/so101-hand.yaml"), &robot).expect("the shipped hand loads");
    let sim = SimRobot::builder(&robot)
        .mounting(mounting)
        .hand(hand)
        .build()
        .expect("simulates");
    let mut bus = sim.driver_buses().remove(0);
    let read = |bus: &mut servobus_driver::Bus<_>, id: u8| {
        let mut b = [0u8; 2];
        bus.read(id, addr::PRESENT_POSITION, &mut b)
            .expect("a reply");
        i32::from(u16::from_le_bytes(b))
    };
    // Figures from the files: lift zero 3900 rising positive, elbow zero
    // 2500 reversed; the hand holds -90/90 until 2 s, 40/-30 at 5..7 s.
    assert_eq!(read(&mut bus, 2), raw(3900.0, 1.0, -90.0));
    assert_eq!(read(&mut bus, 3), raw(2500.0, -1.0, 90.0));
    bus.clock().advance_to(Duration::from_secs(6));
    let lift = read(&mut bus, 2);
    assert!(
        tick_diff(lift, raw(3900.0, 1.0, 40.0)).abs() <= 1.0,
        "{lift}"
    );
    assert!(lift < 400, "past the seam: {lift}");
    let elbow = read(&mut bus, 3);
    assert!(
        tick_diff(elbow, raw(2500.0, -1.0, -30.0)).abs() <= 1.0,
        "{elbow}"
    );
}

#[test]
fn a_random_unit_crosses_the_seam_and_reverses_a_joint() {
    let robot = common::robot("so101.yaml");
    for seed in 0..20 {
        let m = Mounting::random(&robot, seed);
        assert_eq!(m, Mounting::random(&robot, seed), "same seed, same unit");
        let mut crossing = 0;
        let mut reversed = 0;
        for (j, mount) in robot.joints().zip(m.mounts()) {
            let a = mount.zero_tick + mount.direction * j.min * TPD;
            let b = mount.zero_tick + mount.direction * j.max * TPD;
            if (a.min(b) / 4096.0).floor() != (a.max(b) / 4096.0).floor() {
                crossing += 1;
            }
            if mount.direction < 0.0 {
                reversed += 1;
            }
            let [lo, hi] = mount.stops.expect("stops");
            assert!(lo < j.min && hi > j.max, "stops outside the limits");
        }
        assert!(crossing >= 1, "seed {seed}: no range crosses the seam");
        assert!(reversed >= 1, "seed {seed}: no reversed joint");
    }
    assert_ne!(Mounting::random(&robot, 1), Mounting::random(&robot, 2));
}

#[test]
fn without_a_mounting_the_truth_is_the_robot_files_frame() {
    // The design mounting (no file): a played motion ends where its last
    // keyframe says, in the truth's physical angles.
    let (path, robot) = common::motion("arm-wave.yaml");
    let truth = new_truth(&robot);
    let sim = SimRobot::builder(&robot)
        .pose(&common::start_pose(&robot, &path))
        .truth(&truth)
        .build()
        .expect("simulates");
    let report = VirtualRun::new(&robot, path.clone(), sim.driver_buses(), common::quiet())
        .expect("starts")
        .run();
    assert!(report.cycles > 100);
    sim.buses()[0].clock().advance(Duration::from_millis(500));
    sim.settle();
    let mut end = vec![JointState::default(); robot.joint_count()];
    path.sample(path.duration(), &mut end);
    let rows = truth.rows();
    let last = rows.last().expect("rows");
    for (i, j) in robot.joints().enumerate() {
        let want = robot.units.from_rad(end[i].position);
        let got = last.angles_deg[i];
        assert!(
            (got - want).abs() < 1.0,
            "{}: truth {got}, path {want}",
            j.name
        );
    }
}

#[test]
fn truth_rows_have_the_header_and_come_at_100_hz() {
    let robot = common::robot("so101.yaml");
    let truth = new_truth(&robot);
    let hand = Hand::from_keyframes(&robot, &[(0.5, vec![(0, 0.0)]), (1.5, vec![(0, 30.0)])]);
    let sim = SimRobot::builder(&robot)
        .mounting(Mounting::random(&robot, 3))
        .hand(hand)
        .truth(&truth)
        .build()
        .expect("simulates");
    assert_eq!(
        truth.csv_header(),
        "time_s,shoulder_pan,shoulder_lift,elbow_flex,wrist_flex,wrist_roll,gripper"
    );
    sim.buses()[0].clock().advance(Duration::from_secs(3));
    sim.settle();
    let rows = truth.rows();
    let per_second = (rows.len() - 1) as f64 / rows.last().expect("rows").time_s;
    assert!(per_second >= 50.0, "{per_second} rows a second");
    let at = |t: f64| {
        rows.iter()
            .find(|r| (r.time_s - t).abs() < 1e-9)
            .expect("a row")
    };
    assert!((at(1.0).angles_deg[0] - 15.0).abs() < 0.01);
    assert!((at(2.0).angles_deg[0] - 30.0).abs() < 0.01);
    // The rest pose of the other joints is physical, whatever the mounting.
    assert_eq!(at(2.0).angles_deg[1], -90.0);
}

fn load_error(yaml: &str, hand: bool) -> ConfigError {
    let robot = common::robot("so101.yaml");
    let dir = std::env::temp_dir().join(format!("servobus-body-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join(format!("{}.yaml", yaml.len()));
    std::fs::write(&file, yaml).expect("writes");
    let err = if hand {
        Hand::load(&file, &robot).err()
    } else {
        Mounting::load(&file, &robot).err()
    };
    err.expect("refused")
}

#[test]
fn bad_body_files_are_refused_with_file_line_and_field() {
    let cases: [(&str, bool, usize, &str); 6] = [
        (
            "shoulder_pan: {zero_tick: 10}\nelbo: {zero_tick: 1}\n",
            false,
            2,
            "elbo",
        ),
        (
            "gripper: {zero_tick: 10, direction: 2}\n",
            false,
            1,
            "gripper.direction",
        ),
        (
            "\ngripper: {zero_tick: 4096}\n",
            false,
            2,
            "gripper.zero_tick",
        ),
        (
            "gripper: {zero_tick: 1, stops: [10, -10]}\n",
            false,
            1,
            "gripper.stops",
        ),
        (
            "keyframes:\n  - {at: 1, pose: {gripper: 3}}\n  - {at: 1, pose: {gripper: 4}}\n",
            true,
            3,
            "keyframes[1].at",
        ),
        (
            "keyframes:\n  - at: 0\n    pose: {grip: 3}\n",
            true,
            3,
            "keyframes[0].pose.grip",
        ),
    ];
    for (yaml, hand, line, field) in cases {
        let e = load_error(yaml, hand);
        assert_eq!(e.field(), Some(field), "{e}");
        assert_eq!(e.position().map(|p| p.0), Some(line), "{e}");
        assert!(e.to_string().contains(".yaml:"), "{e}");
    }
}

#[test]
fn every_built_in_mounting_and_hand_loads_for_its_robot() {
    use servobus_runtime::config::builtin::{self, Kind};
    let so101 = common::robot("so101.yaml");
    let mut loaded = 0;
    for b in builtin::all() {
        match b.kind {
            Kind::Mounting => drop(Mounting::load(&b.path(), &so101).expect("mounting loads")),
            Kind::Hand => drop(Hand::load(&b.path(), &so101).expect("hand loads")),
            Kind::Robot | Kind::Motion => continue,
        }
        loaded += 1;
    }
    assert!(loaded >= 3, "the so101's mounting and hands: {loaded}");
}
