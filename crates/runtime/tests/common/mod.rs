//! Shared helpers of the runtime's tests: robots and simulated buses.
#![allow(dead_code)]

use std::time::Duration;

use servobus_driver::{Bus, Clock, ManualClock, Transport, TransportError};
use servobus_runtime::config::{
    load_motion, load_robot, plan_motion, JointMap, Robot, RobotOptions,
};
use servobus_runtime::{bus_settings, RunOptions};
use servobus_sim::{SimBus, SimModel, SimServo, WallBus};
use servobus_trajectory::{JointState, Trajectory};

// The shipped files and scratch files, as the configuration's tests have
// them.
#[path = "../../../config/tests/common/mod.rs"]
mod files;
#[allow(unused_imports)] // not every test uses every helper
pub use files::{config, temp_file, temp_path};

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

/// The cycle (of `period` seconds) at which joint `j` of `path` moves
/// fastest: where a fault does the most harm.
pub fn fastest_cycle(path: &Trajectory, j: usize, period: f64) -> u64 {
    let mut s = vec![JointState::default(); path.joints()];
    let mut best = (0.0, 0u64);
    let mut k = 0u64;
    while (k as f64) * period < path.duration() {
        path.sample(k as f64 * period, &mut s);
        if s[j].velocity.abs() > best.0 {
            best = (s[j].velocity.abs(), k);
        }
        k += 1;
    }
    best.1
}

/// One simulated bus per robot bus, each with its own clock, every servo
/// at the middle of its range (tick 2048 on an STS3215).
pub fn sim_buses(robot: &Robot) -> (Vec<Bus<SimBus, ManualClock>>, Vec<SimBus>) {
    let mid: Vec<f64> = robot
        .joints()
        .map(|j| {
            let map = JointMap::new(j, robot.units);
            let mid = i32::try_from(j.model.resolution / 2).expect("a small resolution");
            robot.units.from_rad(map.from_ticks(mid))
        })
        .collect();
    split(robot, simulated(robot, &mid))
}

/// Driver buses on `sims` (in virtual time), with the simulated buses.
fn split(robot: &Robot, sims: Vec<SimBus>) -> (Vec<Bus<SimBus, ManualClock>>, Vec<SimBus>) {
    (buses_on(robot, &sims, SimBus::clone), sims)
}

/// `robot`'s servos as bare shafts at `pose` (one angle per joint in the
/// robot's units, at the robot file's ticks), one [`SimBus`] per robot bus
/// on its own clock, each servo with its ID and model, the bus's return
/// delay and baud rate: what `servobus_robot::sim::SimRobot` builds without
/// a body. The scheduler carries no simulator glue; its tests put the
/// servos on the simulator here.
pub fn simulated(robot: &Robot, pose: &[f64]) -> Vec<SimBus> {
    assert_eq!(pose.len(), robot.joint_count(), "one angle per joint");
    robot
        .buses
        .iter()
        .map(|bus| {
            let baud =
                servobus_protocol::registers::baud_index(bus.baud).expect("a servo baud rate");
            let servos = bus.joints.iter().map(|joint| {
                let model = SimModel::by_number(joint.model.number)
                    .or_else(|| SimModel::by_name(joint.model.name))
                    .expect("the simulator has the model");
                let angle = robot
                    .joints()
                    .position(|j| j.name == joint.name)
                    .map_or(joint.rest(), |i| pose[i]);
                let map = JointMap::new(joint, robot.units);
                SimServo::new(model, joint.id)
                    .with_return_delay(bus.return_delay)
                    .with_byte(servobus_sim::addr::BAUD_RATE, baud)
                    .with_position(map.to_ticks(robot.units.to_rad(angle)))
            });
            SimBus::new(ManualClock::new(), bus.baud).with_servos(servos)
        })
        .collect()
}

/// One driver bus per simulated bus of `robot`, on the transport `on` makes
/// of it, with the robot file's driver settings.
fn buses_on<T: Transport>(
    robot: &Robot,
    sims: &[SimBus],
    on: impl Fn(&SimBus) -> T,
) -> Vec<Bus<T, T::Clock>> {
    sims.iter()
        .zip(&robot.buses)
        .map(|(sim, bus)| Bus::new(on(sim), bus_settings(bus)))
        .collect()
}

/// Driver buses on `robot`'s servos at `pose` ([`simulated`]) paced by the
/// wall clock `clock` ([`WallBus`]: the servos answer in real time, in this
/// process). Give the run the same clock.
pub fn wall_buses<C: Clock>(robot: &Robot, pose: &[f64], clock: &C) -> Vec<Bus<WallBus<C>, C>> {
    buses_on(robot, &simulated(robot, pose), |sim| {
        WallBus::new(sim.clone(), clock.clone())
    })
}

/// Seconds as a Duration.
pub fn secs(s: f64) -> Duration {
    Duration::from_secs_f64(s)
}

/// Like [`sim_buses`], with every servo already at the path's start.
pub fn sim_buses_at(
    robot: &Robot,
    path: &Trajectory,
) -> (Vec<Bus<SimBus, ManualClock>>, Vec<SimBus>) {
    split(robot, simulated(robot, &start_pose(robot, path)))
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
pub fn record<T: servobus_driver::Transport>(
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
pub fn record_acting_at<T: servobus_driver::Transport>(
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

/// What a [`Tapped`] bus does with each frame written, before its inner
/// transport takes it: it sees that transport too (to inject a fault into
/// a simulator).
pub type Tap<T> = Box<dyn FnMut(&T, &[u8]) + Send>;

/// A transport (a simulated bus, in these tests) that shows every frame
/// written to its tap first: to decode the goals on the wire, or to act
/// at a given frame.
pub struct Tapped<T = SimBus> {
    inner: T,
    tap: Tap<T>,
}

impl<T> Tapped<T> {
    /// `inner`, each frame written shown to `tap` first.
    pub fn new(inner: T, tap: impl FnMut(&T, &[u8]) + Send + 'static) -> Self {
        Tapped {
            inner,
            tap: Box::new(tap),
        }
    }
}

impl<T: Transport> Transport for Tapped<T> {
    type Clock = T::Clock;
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        (self.tap)(&self.inner, bytes);
        self.inner.write_all(bytes)
    }
    fn clock(&self) -> &T::Clock {
        self.inner.clock()
    }
    fn baud(&self) -> u32 {
        self.inner.baud()
    }
    fn read(&mut self, buf: &mut [u8], deadline: Duration) -> Result<usize, TransportError> {
        self.inner.read(buf, deadline)
    }
    fn discard_input(&mut self) -> Result<(), TransportError> {
        self.inner.discard_input()
    }
}
