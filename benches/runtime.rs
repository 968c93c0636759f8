//! Benches of servobus-runtime: whole runs in virtual time on the simulated
//! buses, start-up included (the cost of the scheduler, the tracking and the
//! simulator together, per run of a few thousand cycles).

use std::path::Path;

use criterion::Criterion;
use servobus_driver::Bus;
use servobus_robot::sim::SimRobot;
use servobus_runtime::config::{load_motion, plan_motion, Robot};
use servobus_runtime::{Finish, RunOptions, VirtualRun};
use servobus_sim::SimBus;
use servobus_trajectory::Trajectory;

fn motion(motion: &str, robot: Option<&str>) -> (Trajectory, Robot) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
    let robot = robot.map(|r| root.join("robots").join(r));
    let (m, r) = match load_motion(&root.join("motions").join(motion), robot.as_deref()) {
        Ok(mr) => mr,
        Err(e) => panic!("bench motion does not load: {e}"),
    };
    match plan_motion(&m, &r) {
        Ok(t) => (t, r),
        Err(e) => panic!("bench motion does not plan: {e}"),
    }
}

/// The robot's simulator (servos at rest), one bus per robot bus.
fn buses(robot: &Robot) -> Vec<Bus<SimBus>> {
    match SimRobot::builder(robot).build() {
        Ok(sim) => sim.driver_buses(),
        Err(e) => panic!("bench robot does not simulate: {e}"),
    }
}

/// A whole run; it must complete, or the figure would time a fault.
fn run(path: &Trajectory, robot: &Robot) -> u64 {
    let options = RunOptions {
        telemetry_capacity: 0,
        ..RunOptions::default()
    };
    let report = match VirtualRun::new(robot, path.clone(), buses(robot), options) {
        Ok(r) => r.run(),
        Err(e) => panic!("bench run does not start: {e}"),
    };
    assert_eq!(report.finish, Finish::Completed, "{:?}", report.fault);
    report.cycles
}

/// Registers the benches of this module.
pub fn benches(c: &mut Criterion) {
    let mut g = c.benchmark_group("runtime");
    g.sample_size(10);
    let (arm, so101) = motion("arm-wave.yaml", None);
    g.bench_function("virtual_run/arm_wave", |b| b.iter(|| run(&arm, &so101)));
    let (walk, hexapod) = motion("hexapod-tripod.yaml", Some("hexapod-2bus.yaml"));
    g.bench_function("virtual_run/hexapod_2bus", |b| {
        b.iter(|| run(&walk, &hexapod))
    });
    g.finish();
}
