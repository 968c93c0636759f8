//! Helpers of the scheduler's tests that need no simulator: robot files
//! and planned motions from `configs/`, run options, and the telemetry of
//! a virtual-time run recorded and checked against the SO-101's limits.
//! The runtime's tests and the facade's (`crates/robot/tests`) both use
//! this file; each parent module provides `config` (a path under
//! `configs/`).
#![allow(dead_code)]

use servobus_runtime::config::{load_motion, load_robot, plan_motion, Robot, RobotOptions};
use servobus_runtime::RunOptions;
use servobus_trajectory::{JointState, Trajectory};

use super::config;

/// The SO-101's limits by hand (configs/robots/so101.yaml): velocity,
/// acceleration, jerk in deg/s, deg/s^2, deg/s^3, in its joint order.
pub const SO101_LIMITS: [(f64, f64, f64); 6] = [
    (180.0, 900.0, 9000.0),
    (150.0, 700.0, 7000.0),
    (180.0, 900.0, 9000.0),
    (240.0, 1200.0, 12000.0),
    (270.0, 1500.0, 15000.0),
    (240.0, 1500.0, 15000.0),
];

/// A robot file under `configs/robots/`.
pub fn robot(name: &str) -> Robot {
    load_robot(&config(&format!("robots/{name}")), &RobotOptions::default())
        .expect("robot file loads")
}

/// A motion under `configs/motions/`, planned, with its robot.
pub fn motion(name: &str) -> (Trajectory, Robot) {
    planned(&format!("motions/{name}"), None)
}

/// The motion file `motion` under `configs/`, planned for the robot file
/// `robot` under `configs/` (or the one the motion names), with the robot.
pub fn planned(motion: &str, robot: Option<&str>) -> (Trajectory, Robot) {
    let robot = robot.map(config);
    let (m, r) = load_motion(&config(motion), robot.as_deref()).expect("motion loads");
    let t = plan_motion(&m, &r).expect("motion plans");
    (t, r)
}

/// Where `path` starts, per joint in the robot's units.
pub fn start_pose(robot: &Robot, path: &Trajectory) -> Vec<f64> {
    let mut start = vec![JointState::default(); robot.joint_count()];
    path.sample(0.0, &mut start);
    start
        .iter()
        .map(|s| robot.units.from_rad(s.position))
        .collect()
}

/// Run options without telemetry, for tests that read only the report.
pub fn quiet() -> RunOptions {
    RunOptions {
        telemetry_capacity: 0,
        ..RunOptions::default()
    }
}

/// Every telemetry cycle sample of a run, collected by stepping it.
pub struct Recorded {
    /// `(cycle, joint, commanded, error, measured)` in report units.
    pub rows: Vec<(u64, usize, f64, f64, Option<f64>)>,
    /// Faults published.
    pub faults: Vec<servobus_runtime::Fault>,
    /// Live-target events published, with their time (s).
    pub live: Vec<(servobus_runtime::LiveEvent, f64)>,
}

/// Steps `run` until it ends or `max` cycles pass, calling `each(cycle)`
/// before every step, and records the telemetry.
pub fn record<T: servobus_driver::Transport<Clock = servobus_driver::ManualClock>>(
    run: &mut servobus_runtime::VirtualRun<T>,
    max: u64,
    mut each: impl FnMut(u64),
) -> Recorded {
    use servobus_runtime::Telemetry;
    let rx = run.telemetry();
    let mut rec = Recorded {
        rows: Vec::new(),
        faults: Vec::new(),
        live: Vec::new(),
    };
    let drain = |rec: &mut Recorded| {
        while let Ok(m) = rx.try_recv() {
            match m {
                Telemetry::Cycle(c) => {
                    for j in c.joints() {
                        rec.rows
                            .push((c.cycle, j.joint, j.commanded, j.error, j.measured));
                    }
                }
                Telemetry::Fault(f) => rec.faults.push(f),
                Telemetry::Live { event, time_s } => rec.live.push((event, time_s)),
                _ => {}
            }
        }
    };
    for _ in 0..max {
        each(run.cycle());
        let going = run.step();
        drain(&mut rec);
        if !going {
            break;
        }
    }
    rec
}

/// [`record`], doing `act` once, just before cycle `at` (a fault injected,
/// a command sent).
pub fn record_acting_at<T: servobus_driver::Transport<Clock = servobus_driver::ManualClock>>(
    run: &mut servobus_runtime::VirtualRun<T>,
    max: u64,
    at: u64,
    act: impl FnOnce(),
) -> Recorded {
    let mut act = Some(act);
    record(run, max, |k| {
        if let Some(act) = act.take_if(|_| k == at) {
            act();
        }
    })
}

impl Recorded {
    /// The commanded positions of `joint`, one per cycle.
    pub fn commanded(&self, joint: usize) -> Vec<f64> {
        self.rows
            .iter()
            .filter(|r| r.1 == joint)
            .map(|r| r.2)
            .collect()
    }

    /// Largest |first, second, third difference| / period^n of `joint`'s
    /// commands from cycle `from` on: velocity, acceleration, jerk.
    pub fn peaks(&self, joint: usize, from: u64, period: f64) -> (f64, f64, f64) {
        let c: Vec<f64> = self
            .rows
            .iter()
            .filter(|r| r.1 == joint && r.0 >= from)
            .map(|r| r.2)
            .collect();
        let d = |v: &[f64]| v.windows(2).map(|w| w[1] - w[0]).collect::<Vec<_>>();
        let d1 = d(&c);
        let d2 = d(&d1);
        let d3 = d(&d2);
        let m = |v: &[f64], p: i32| v.iter().fold(0.0f64, |a, x| a.max(x.abs())) / period.powi(p);
        (m(&d1, 1), m(&d2, 2), m(&d3, 3))
    }

    /// Asserts that every joint of an SO-101 run ([`SO101_LIMITS`]) stays
    /// within its limits from cycle `from` on, by finite differences of its
    /// goals at `period` s (1 % for rounding of the differences).
    pub fn assert_within_so101_limits(&self, from: u64, period: f64) {
        for (j, &(v, a, jerk)) in SO101_LIMITS.iter().enumerate() {
            let (pv, pa, pj) = self.peaks(j, from, period);
            assert!(pv <= v * 1.01, "joint {j}: speed {pv} > {v}");
            assert!(pa <= a * 1.01, "joint {j}: acceleration {pa} > {a}");
            assert!(pj <= jerk * 1.01, "joint {j}: jerk {pj} > {jerk}");
        }
    }
}
