//! Shared helpers of the runtime's tests: robots and simulated buses.
#![allow(dead_code)]

use std::time::Duration;

use servobus_driver::{Bus, Clock, ManualClock, Transport, TransportError};
use servobus_runtime::config::{JointMap, Robot};
use servobus_runtime::{bus_settings, Lead, RunOptions, VirtualRun};
use servobus_sim::{SimBus, SimModel, SimServo, WallBus};
use servobus_trajectory::{JointState, Trajectory};

// The shipped files and scratch files, as the configuration's tests have
// them.
#[path = "../../../config/tests/common/mod.rs"]
mod files;
#[allow(unused_imports)] // not every test uses every helper
pub use files::{config, temp_file, temp_path};

// Robot files, planned motions and recorded telemetry: shared with the
// facade's tests, which run the scheduler on its simulator backends.
mod runs;
pub use runs::*;

/// A live run of the simulated SO-101, no lead and no approach, and its
/// robot file.
pub fn live_so101() -> (VirtualRun<SimBus>, Robot) {
    let robot = robot("so101.yaml");
    let (buses, _) = sim_buses(&robot);
    let options = RunOptions {
        lead: Lead::None,
        approach: None,
        ..RunOptions::default()
    };
    let run = VirtualRun::live(&robot, buses, options).expect("a live run starts");
    (run, robot)
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
pub fn sim_buses(robot: &Robot) -> (Vec<Bus<SimBus>>, Vec<SimBus>) {
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
fn split(robot: &Robot, sims: Vec<SimBus>) -> (Vec<Bus<SimBus>>, Vec<SimBus>) {
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
) -> Vec<Bus<T>> {
    sims.iter()
        .zip(&robot.buses)
        .map(|(sim, bus)| Bus::new(on(sim), bus_settings(bus)))
        .collect()
}

/// Driver buses on `robot`'s servos at `pose` ([`simulated`]) paced by the
/// wall clock `clock` ([`WallBus`]: the servos answer in real time, in this
/// process). Give the run the same clock.
pub fn wall_buses<C: Clock>(robot: &Robot, pose: &[f64], clock: &C) -> Vec<Bus<WallBus<C>>> {
    buses_on(robot, &simulated(robot, pose), |sim| {
        WallBus::new(sim.clone(), clock.clone())
    })
}

/// Seconds as a Duration.
pub fn secs(s: f64) -> Duration {
    Duration::from_secs_f64(s)
}

/// Like [`sim_buses`], with every servo already at the path's start.
pub fn sim_buses_at(robot: &Robot, path: &Trajectory) -> (Vec<Bus<SimBus>>, Vec<SimBus>) {
    split(robot, simulated(robot, &start_pose(robot, path)))
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
