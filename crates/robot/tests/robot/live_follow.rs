//! A leader arm driving a follower through live targets, both simulated in
//! virtual time: the built-in hand (configs/sim/so101-hand.yaml) moves the
//! leader's torque-off joints, its positions are read at 50 Hz (as
//! `servobus follow` reads them) and sent to the follower's live run, and
//! the follower's measured positions stay within 2 degrees of the leader's
//! true positions (the hand's) one target interval and the servo's
//! response lag before, from 0.5 s on. The follower's lead is
//! identified as `servobus follow`'s is (a robot file with no `lead_ms`).

use crate::common;

use common::{config, record, robot};
use servobus_driver::{Bus, Clock};
use servobus_robot::sim::{Hand, SimRobot};
use servobus_runtime::config::{JointMap, Robot};
use servobus_runtime::{Lead, LiveTarget, RunOptions, VirtualRun};
use servobus_sim::SimBus;

const PERIOD: f64 = 0.005;

/// How far the follower trails the leader by design, s: one target
/// interval (the leader is read at 50 Hz, and nothing is extrapolated
/// past the newest reading) and the servo's response lag (10 ms).
const FOLLOWED_LAG: f64 = 0.020 + 0.010;

/// The leader's angles now (deg), one per joint.
fn read_leader(robot: &Robot, bus: &mut Bus<SimBus>) -> Vec<f64> {
    let reg = bus
        .settings()
        .series
        .map()
        .get("present_position")
        .expect("a position register");
    robot
        .joints()
        .map(|j| {
            let (ticks, _) = bus.read_register(j.id, reg).expect("the leader answers");
            robot
                .units
                .from_rad(JointMap::new(j, robot.units).from_ticks(ticks))
        })
        .collect()
}

#[test]
fn a_follower_stays_within_2_degrees_of_a_hand_moved_leader() {
    let robot = robot("so101.yaml");
    let hand = Hand::load(&config("sim/so101-hand.yaml"), &robot).expect("the built-in hand");
    let leader_sim = SimRobot::builder(&robot)
        .hand(hand.clone())
        .build()
        .expect("the leader simulates");
    let mut leader = leader_sim.driver_buses().remove(0);
    // The follower starts where the hand holds the leader at first.
    let start = read_leader(&robot, &mut leader);
    let follower = SimRobot::builder(&robot)
        .pose(&start)
        .build()
        .expect("the follower simulates");
    // As `servobus follow` runs it.
    let options = RunOptions {
        lead: Lead::default(),
        approach: None,
        ..RunOptions::default()
    };
    let mut run =
        VirtualRun::live(&robot, follower.driver_buses(), options).expect("a live run starts");
    let tx = run.targets();
    let names: Vec<String> = robot.joints().map(|j| j.name.clone()).collect();
    let t0 = leader.clock().now();
    let mut readings: Vec<(u64, Vec<f64>)> = Vec::new();
    // 6 s: held, then the arm raised between 2 and 5 s.
    let rec = record(&mut run, 1200, |k| {
        let t = k as f64 * PERIOD;
        leader
            .clock()
            .sleep_until(t0 + std::time::Duration::from_secs_f64(t));
        let pose = read_leader(&robot, &mut leader);
        if k % 4 == 0 {
            let joints = names
                .iter()
                .zip(&pose)
                .map(|(n, a)| (n.clone(), a.to_radians()))
                .collect();
            tx.send(LiveTarget::named(t, joints))
                .expect("a good target");
        }
        readings.push((k, pose));
    });
    assert!(rec.faults.is_empty(), "{:?}", rec.faults);
    // Against the hand's angle (the robot's units are degrees, and it has
    // no calibration: the physical angle is the joint's).
    let mut worst = vec![0.0f64; names.len()];
    let mut squares = vec![(0.0f64, 0u32); names.len()];
    for &(k, joint, _, _, measured) in &rec.rows {
        let t = k as f64 * PERIOD;
        let (Some(m), Some(truth)) = (
            measured,
            hand.path(joint).and_then(|p| p.angle_at(t - FOLLOWED_LAG)),
        ) else {
            continue;
        };
        if t < 0.5 {
            continue;
        }
        let e = m - truth;
        worst[joint] = worst[joint].max(e.abs());
        squares[joint] = (squares[joint].0 + e * e, squares[joint].1 + 1);
    }
    let rms: Vec<f64> = squares
        .iter()
        .map(|(s, n)| (s / f64::from((*n).max(1))).sqrt())
        .collect();
    println!(
        "error per joint, deg: largest {worst:.2?}, RMS {rms:.2?}; lead {:.1} ms",
        run.report().lead_ms
    );
    for (j, (w, r)) in worst.iter().zip(&rms).enumerate() {
        assert!(
            squares[j].1 > 1000,
            "{}: {} readings",
            names[j],
            squares[j].1
        );
        assert!(*w < 2.0, "{}: {w} deg", names[j]);
        assert!(*r < 0.5, "{}: RMS {r} deg", names[j]);
    }
    // The leader did move: the lift rose by more than 100 degrees.
    let lift: Vec<f64> = readings.iter().map(|r| r.1[1]).collect();
    let rise = lift.iter().fold(f64::MIN, |a, b| a.max(*b)) - lift[0];
    assert!(rise > 100.0, "{rise}");
}
