//! End to end in virtual time, on the simulator's body: robots whose servo
//! horns are fitted at random angles (some ranges across the 4095 -> 0
//! seam, some directions reversed) are calibrated by a scripted hand
//! through the procedure `servobus calibrate` runs, then play a motion; the
//! body's true angles are compared with the motion's keyframes. Without the
//! calibration the same motion is refused or misses by tens of degrees.

use crate::calib_play;
use crate::common;

use std::path::Path;
use std::time::Duration;

use servobus_driver::{Bus, Clock, ManualClock};
use servobus_robot::calibrate::{calibrate, prepare_servos, LiveJoint, Operator, Step};
use servobus_robot::sim::Mounting;
use servobus_runtime::config::{
    load_robot, save_calibration, Calibration, JointMap, Robot, RobotOptions,
};
use servobus_runtime::{bus_settings, Finish};
use servobus_sim::body::{HandPath, Mount};
use servobus_sim::{SimBus, SimServo};

/// A robot as it comes off a careless assembly (`servobus sim --unit
/// SEED`): horns anywhere on the turn, at least one range across the seam,
/// at least one direction reversed, stops 5 degrees beyond the limits.
fn random_mounts(robot: &Robot, seed: u64) -> Vec<Mount> {
    let mounts = Mounting::random(robot, seed).mounts().to_vec();
    let crosses = |m: &Mount| {
        let [lo, hi] = m.stops.expect("stops");
        let a = m.zero_tick + m.direction * lo / DEG_PER_TICK;
        let b = m.zero_tick + m.direction * hi / DEG_PER_TICK;
        (a.min(b) / 4096.0).floor() != (a.max(b) / 4096.0).floor()
    };
    assert!(mounts.iter().any(crosses), "a range across the seam");
    assert!(mounts.iter().any(|m| m.direction < 0.0), "a reversed joint");
    mounts
}

const DEG_PER_TICK: f64 = 360.0 / 4096.0;

/// The hand's script: from `start`, to the calibration pose (all 0) and
/// held, then each joint in turn to its upper stop, its lower stop and back
/// (a moment at each stop), then held; let go at the end.
fn hand_paths(mounts: &[Mount], start: &[f64]) -> (Vec<HandPath>, f64) {
    let sweep_start = 4.5;
    let per_joint = 4.0;
    let end = sweep_start + per_joint * mounts.len() as f64 + 3.0;
    let paths = mounts
        .iter()
        .zip(start)
        .enumerate()
        .map(|(j, (m, &from))| {
            let [lo, hi] = m.stops.expect("stops");
            let t = sweep_start + per_joint * j as f64;
            HandPath::new([
                (0.5, from),
                (1.5, 0.0),
                (t, 0.0),
                (t + 1.0, hi),
                (t + 1.2, hi),
                (t + 2.7, lo),
                (t + 2.9, lo),
                (t + 3.9, 0.0),
                (end, 0.0),
            ])
        })
        .collect();
    (paths, end)
}

/// The robot's single bus of mounted servos, each joint at `start` degrees,
/// with the hand's paths when given.
fn body(
    robot: &Robot,
    mounts: &[Mount],
    start: &[f64],
    hands: Option<Vec<HandPath>>,
) -> (Vec<Bus<SimBus>>, SimBus) {
    let bus = &robot.buses[0];
    let clock = ManualClock::new();
    let mut hands = hands.map(Vec::into_iter);
    let servos: Vec<SimServo> = bus
        .joints
        .iter()
        .zip(mounts)
        .zip(start)
        .map(|((j, &m), &a)| {
            let servo = SimServo::sts3215(j.id)
                .with_return_delay(bus.return_delay)
                .with_mount(m, a);
            match hands.as_mut().and_then(Iterator::next) {
                Some(hand) => servo.with_hand(hand),
                None => servo,
            }
        })
        .collect();
    let sim = SimBus::new(clock.clone(), bus.baud).with_servos(servos);
    (vec![Bus::new(sim.clone(), bus_settings(bus))], sim)
}

/// The body's physical angles, robot joint order.
fn truth(robot: &Robot, sim: &SimBus) -> Vec<f64> {
    robot
        .joints()
        .map(|j| {
            sim.servo(j.id, |s| s.joint_angle())
                .flatten()
                .expect("mounted")
        })
        .collect()
}

/// An operator who never presses Enter: the steps end on stillness.
struct Script(Vec<Step>);

impl Operator for Script {
    fn step(&mut self, step: Step) {
        self.0.push(step);
    }
    fn watch(&mut self, _at: Duration, _joints: &[LiveJoint]) {}
    fn confirmed(&mut self) -> bool {
        false
    }
}

/// Calibrates `robot_file`'s robot, mounted by `mounts`, with the hand;
/// returns the calibration and the buses, the hand gone.
fn calibrate_body(
    design: &Robot,
    mounts: &[Mount],
    start: &[f64],
) -> (Calibration, Vec<Bus<SimBus>>, SimBus) {
    let (hands, end) = hand_paths(mounts, start);
    let (mut buses, sim) = body(design, mounts, start, Some(hands));
    let mut script = Script(Vec::new());
    let options = calib_play::procedure(true);
    let cal = calibrate(design, &mut buses, &mut script, &options).expect("calibrates");
    assert_eq!(
        script.0,
        [Step::TorqueOff, Step::HoldPose, Step::Sweep, Step::Done]
    );
    let done = buses[0].clock().now().as_secs_f64();
    assert!(
        done > end - 3.0 && done < end,
        "ended at {done} s, hand let go at {end} s"
    );
    // The person steps back: the hand lets go.
    buses[0]
        .clock()
        .advance_to(Duration::from_secs_f64(end + 0.5));
    (cal, buses, sim)
}

/// Saves `cal` as the file `name`, applies it to the robot of `robot_file`,
/// prepares and checks the servos, and plays `motion` (under `configs/`)
/// on them.
fn play_calibrated(
    robot_file: &Path,
    cal: &Calibration,
    name: &str,
    mounts: &[Mount],
    mut buses: Vec<Bus<SimBus>>,
    sim: &SimBus,
    motion: &str,
) -> calib_play::Played {
    let path = common::temp_path("calibrate_body", name);
    save_calibration(cal, &path).expect("saves");
    let robot = load_robot(
        robot_file,
        &RobotOptions::default().calibration(Some(&path)),
    )
    .expect("applies");
    // Before moving, the servos are checked and those across the seam get
    // their session offset; from then on readings are physical angles.
    prepare_servos(&robot, &mut buses).expect("the servos are the calibrated ones");
    check_calibration(&robot, mounts, sim);
    calib_play::play(
        &common::config(motion),
        robot_file,
        &robot,
        Some(&path),
        buses,
        || truth(&robot, sim),
    )
}

/// Every joint's measured range is its stops, and its reading maps to its
/// physical angle.
fn check_calibration(robot: &Robot, mounts: &[Mount], sim: &SimBus) {
    let now = truth(robot, sim);
    for ((j, m), t) in robot.joints().zip(mounts).zip(now) {
        let c = j.calibration.as_ref().expect("calibrated");
        assert_eq!(f64::from(c.direction), m.direction, "{}", j.name);
        let (lo, hi) = c.range_deg(j.model);
        let [slo, shi] = m.stops.expect("stops");
        assert!(
            (lo - slo).abs() < 0.3 && (hi - shi).abs() < 0.3,
            "{}: measured {lo}..{hi}, stops {slo}..{shi}",
            j.name
        );
        let tick = sim.present_position(j.id).expect("servo");
        let read = JointMap::new(j, robot.units).from_ticks(tick).to_degrees();
        assert!(
            (read - t).abs() < 0.2,
            "{}: reads {read}, is at {t}",
            j.name
        );
    }
}

fn arm_start() -> Vec<f64> {
    vec![35.0, -70.0, 60.0, 25.0, -50.0, 40.0]
}

#[test]
fn a_randomly_fitted_arm_is_calibrated_by_hand_then_plays_within_a_degree() {
    let robot_file = common::config("robots/so101.yaml");
    let design = load_robot(&robot_file, &RobotOptions::default()).expect("so101");
    let mounts = random_mounts(&design, 7);
    let (cal, buses, sim) = calibrate_body(&design, &mounts, &arm_start());
    let crossing: Vec<&str> = cal
        .joints
        .iter()
        .filter(|c| c.crosses_seam())
        .map(|c| c.name.as_str())
        .collect();
    println!("mounts {mounts:?}\nacross the seam: {crossing:?}");
    assert!(!crossing.is_empty(), "a range measured across the seam");
    let played = play_calibrated(
        &robot_file,
        &cal,
        "so101.calibration.yaml",
        &mounts,
        buses,
        &sim,
        "motions/arm-wave.yaml",
    );
    println!(
        "calibrated: {:?}, worst miss at a keyframe {:.3} deg",
        played.finish, played.worst
    );
    assert_eq!(played.finish, Some(Finish::Completed));
    assert_eq!(played.reached, played.keyframes, "every keyframe reached");
    assert!(played.worst < 1.0, "misses by {:.2} deg", played.worst);

    // The same body, the same motion, without the calibration.
    let (buses, sim) = body(&design, &mounts, &[0.0; 6], None);
    // Read through the design's mapping, joints that are all at 0 appear
    // tens of degrees away...
    let misread = design
        .joints()
        .map(|j| {
            let tick = sim.present_position(j.id).expect("servo");
            JointMap::new(j, design.units)
                .from_ticks(tick)
                .to_degrees()
                .abs()
        })
        .fold(0.0, f64::max);
    assert!(
        misread > 30.0,
        "design readings off by only {misread:.1} deg"
    );
    // ...so the motion is stopped by a fault before it plays, or misses.
    let played = calib_play::play(
        &common::config("motions/arm-wave.yaml"),
        &robot_file,
        &design,
        None,
        buses,
        || truth(&design, &sim),
    );
    let most = played.keyframes.saturating_sub(1);
    calib_play::assert_uncalibrated_fails(&played, misread, most);
}

#[test]
fn a_randomly_fitted_hexapod_calibrates_and_plays() {
    let robot_file = common::config("robots/hexapod.yaml");
    let design = load_robot(&robot_file, &RobotOptions::default()).expect("hexapod");
    let mounts = random_mounts(&design, 11);
    // Legs wherever they were left: a spread of angles inside the limits.
    let start: Vec<f64> = design
        .joints()
        .enumerate()
        .map(|(i, j)| j.min + (j.max - j.min) * ((i * 7 % 11) as f64 / 11.0))
        .collect();
    let (cal, buses, sim) = calibrate_body(&design, &mounts, &start);
    assert!(cal.joints.iter().any(|c| c.crosses_seam()));
    let played = play_calibrated(
        &robot_file,
        &cal,
        "hexapod.calibration.yaml",
        &mounts,
        buses,
        &sim,
        "motions/hexapod-tripod.yaml",
    );
    println!(
        "hexapod: {:?}, worst miss at a keyframe {:.3} deg",
        played.finish, played.worst
    );
    assert_eq!(played.finish, Some(Finish::Completed));
    assert!(played.worst < 1.0, "misses by {:.2} deg", played.worst);
}
