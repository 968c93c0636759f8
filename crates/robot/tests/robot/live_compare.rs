//! The comparison: the same 30 Hz target stream sent as raw goals (each
//! target written straight to Goal_Position, as LeRobot's teleoperation
//! writes them) and through the live-target loop (`servobus stream`), both
//! on the simulated SO-101 in virtual time. The simulator's truth (the
//! physical angle of the base, sampled every 10 ms) gives the measured
//! motion; its RMS jerk and peak acceleration are printed for each, and the
//! stream's are the lower.

use crate::common;

use std::time::Duration;

use common::robot;
use servobus_driver::Clock;
use servobus_robot::sim::{new_truth, SimRobot, TRUTH_PERIOD};
use servobus_runtime::config::{JointMap, Robot};
use servobus_runtime::{Command, Lead, LiveTarget, RunOptions, VirtualRun};
use servobus_sim::Truth;

const PERIOD: f64 = 0.005;
const SECONDS: f64 = 4.0;

/// The teleoperated base angle at `t`, deg: a 0.5 Hz swing of 40 deg.
fn source(t: f64) -> f64 {
    40.0 * (2.0 * std::f64::consts::PI * 0.5 * t).sin()
}

/// The 30 Hz target times.
fn slots() -> Vec<f64> {
    (1..(SECONDS * 30.0) as usize)
        .map(|i| i as f64 / 30.0)
        .collect()
}

/// RMS jerk and peak |acceleration| of the base's truth from 0.5 s to
/// `SECONDS - 0.2`, by finite differences (deg/s^3, deg/s^2).
fn figures(truth: &Truth) -> (f64, f64) {
    let dt = TRUTH_PERIOD.as_secs_f64();
    let rows = truth.rows();
    let q: Vec<f64> = rows
        .iter()
        .filter(|r| r.time_s >= 0.5 && r.time_s <= SECONDS - 0.2)
        .map(|r| r.angles_deg[0])
        .collect();
    let d = |v: &[f64]| v.windows(2).map(|w| (w[1] - w[0]) / dt).collect::<Vec<_>>();
    let acc = d(&d(&q));
    let jerk = d(&acc);
    let rms = (jerk.iter().map(|j| j * j).sum::<f64>() / jerk.len().max(1) as f64).sqrt();
    let peak = acc.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    (rms, peak)
}

/// Raw goals: each target written to the base's Goal_Position when it comes.
fn raw(robot: &Robot) -> (f64, f64) {
    let truth = new_truth(robot);
    let sim = SimRobot::builder(robot)
        .truth(&truth)
        .build()
        .expect("the robot simulates");
    let mut bus = sim.driver_buses().remove(0);
    let joint = robot.joints().next().expect("a base joint");
    let map = JointMap::new(joint, robot.units);
    let regs = bus.settings().series.map();
    let (goal, torque) = (
        regs.get("goal_position").expect("a goal register"),
        regs.get("torque_enable").expect("a torque register"),
    );
    let start = bus.clock().now();
    bus.write_register(joint.id, goal, map.to_ticks(0.0))
        .expect("the servo answers");
    bus.write_register(joint.id, torque, 1)
        .expect("the servo answers");
    for s in slots() {
        bus.clock().sleep_until(start + Duration::from_secs_f64(s));
        let ticks = map.to_ticks(source(s).to_radians());
        bus.write_register(joint.id, goal, ticks)
            .expect("the servo answers");
    }
    bus.clock()
        .sleep_until(start + Duration::from_secs_f64(SECONDS));
    sim.settle();
    figures(&truth)
}

/// The same targets through the live-target loop.
fn streamed(robot: &Robot) -> (f64, f64) {
    let truth = new_truth(robot);
    let sim = SimRobot::builder(robot)
        .truth(&truth)
        .build()
        .expect("the robot simulates");
    let options = RunOptions {
        lead: Lead::None,
        approach: None,
        telemetry_capacity: 0,
        ..RunOptions::default()
    };
    let mut run = VirtualRun::live(robot, sim.driver_buses(), options).expect("a live run");
    let tx = run.targets();
    let slots = slots();
    let mut next = 0;
    let cycles = (SECONDS / PERIOD) as u64;
    while run.cycle() < cycles {
        let now = run.cycle() as f64 * PERIOD;
        while next < slots.len() && slots[next] <= now {
            let s = slots[next];
            let t = LiveTarget::named(s, vec![("shoulder_pan".into(), source(s).to_radians())]);
            tx.send(t).expect("a good target");
            next += 1;
        }
        assert!(run.step(), "the run goes on");
    }
    run.commands().send(Command::Stop).expect("the run listens");
    while run.step() {}
    sim.settle();
    figures(&truth)
}

#[test]
fn streamed_targets_move_the_servo_more_smoothly_than_raw_goals() {
    let robot = robot("so101.yaml");
    let (raw_jerk, raw_acc) = raw(&robot);
    let (stream_jerk, stream_acc) = streamed(&robot);
    println!(
        "30 Hz targets, base, measured (simulator truth at 100 Hz):\n  raw goals: RMS jerk {raw_jerk:.0} deg/s^3, peak acceleration {raw_acc:.0} deg/s^2\n  stream:    RMS jerk {stream_jerk:.0} deg/s^3, peak acceleration {stream_acc:.0} deg/s^2"
    );
    assert!(stream_jerk < raw_jerk, "{stream_jerk} vs {raw_jerk}");
    assert!(stream_acc < raw_acc, "{stream_acc} vs {raw_acc}");
}
