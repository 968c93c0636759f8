//! A node's callbacks on a virtual-time run of the simulated SO-101:
//! payloads as they come off the network go through the node's own
//! callbacks, between the loop's cycles, so every run is the same.

use std::cell::RefCell;
use std::path::PathBuf;
use std::rc::Rc;
use std::time::Instant;

use servobus_robot::config::{load_motion, load_robot, plan_motion, Robot, RobotOptions};
use servobus_robot::sim::virtual_buses;
use servobus_robot::{Command, Finish, Lead, RunOptions, Telemetry, VirtualRun};

use super::relay::{take_command, take_target, Inputs};
use super::{Planner, Shared};

pub(super) fn configs(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../configs")
        .join(path)
}

/// Plans `motion` under `configs/motions/` for the SO-101, as `serve`'s
/// planner does.
fn planner() -> Box<Planner> {
    Box::new(|motion: &str| {
        let path = configs(&format!("motions/{motion}.yaml"));
        let robot = configs("robots/so101.yaml");
        let (m, r) = load_motion(&path, Some(&robot)).map_err(|e| e.to_string())?;
        plan_motion(&m, &r)
            .map(Command::replace)
            .map_err(|e| e.to_string())
    })
}

/// A virtual run, seen through what the tests ask of it (its bus type is
/// the simulator's, which this crate does not name).
pub(super) struct Run {
    /// Runs one cycle: whether the run goes on, and its telemetry.
    pub step: Box<dyn FnMut() -> (bool, Vec<Telemetry>)>,
    /// The next cycle's number.
    pub cycle: Box<dyn Fn() -> u64>,
    /// Why the run ended, once it has.
    pub finished: Box<dyn Fn() -> Option<Finish>>,
    /// The control period, s.
    pub period: f64,
}

/// A live run of the SO-101 in virtual time, and what the node holds of it.
pub(super) struct Node {
    pub robot: Robot,
    pub run: Run,
    pub to: Inputs,
    pub shared: Shared,
    pub planner: Box<Planner>,
    pub started: Instant,
    /// Commanded angles (the robot file's degrees) per cycle, per joint.
    pub commanded: Vec<Vec<f64>>,
}

impl Node {
    pub fn new() -> Node {
        let robot =
            load_robot(&configs("robots/so101.yaml"), &RobotOptions::default()).expect("so101");
        let buses = virtual_buses(&robot).expect("the simulated arm");
        let options = RunOptions {
            lead: Lead::None,
            approach: None,
            ..RunOptions::default()
        };
        let run = VirtualRun::live(&robot, buses, options).expect("a live run");
        let to = Inputs {
            targets: run.targets(),
            commands: run.commands(),
        };
        let rx = run.telemetry();
        let period = run.period().as_secs_f64();
        let run = Rc::new(RefCell::new(run));
        let (a, b, c) = (Rc::clone(&run), Rc::clone(&run), run);
        let run = Run {
            step: Box::new(move || {
                let going = a.borrow_mut().step();
                (going, rx.try_iter().collect())
            }),
            cycle: Box::new(move || b.borrow().cycle()),
            finished: Box::new(move || c.borrow().finished()),
            period,
        };
        Node {
            robot,
            run,
            to,
            shared: Shared::default(),
            planner: planner(),
            started: Instant::now(),
            commanded: Vec::new(),
        }
    }

    pub fn period(&self) -> f64 {
        self.run.period
    }

    pub fn target(&self, payload: &str) {
        let robot = (self.robot.units, Some(&self.robot));
        take_target(
            payload.as_bytes(),
            &self.to,
            robot,
            self.started,
            &self.shared,
        );
    }

    pub fn command(&self, payload: &str) {
        let period = self.period();
        take_command(
            payload.as_bytes(),
            &self.to,
            &*self.planner,
            period,
            &self.shared,
        );
    }

    /// Runs `cycles` cycles (fewer if the run ends), calling `each` with
    /// the cycle's number before it. Returns whether the run goes on.
    pub fn run_for(&mut self, cycles: u64, mut each: impl FnMut(&Node, u64)) -> bool {
        let n = self.robot.joint_count();
        for _ in 0..cycles {
            each(self, (self.run.cycle)());
            let (going, telemetry) = (self.run.step)();
            for m in telemetry {
                if let Telemetry::Cycle(c) = m {
                    let mut row = vec![f64::NAN; n];
                    for j in c.joints() {
                        row[j.joint] = j.commanded;
                    }
                    self.commanded.push(row);
                }
            }
            if !going {
                return false;
            }
        }
        true
    }

    /// The commanded angles of joint `j` from cycle `from` on (deg).
    pub fn joint(&self, j: usize, from: usize) -> Vec<f64> {
        self.commanded[from..].iter().map(|r| r[j]).collect()
    }

    /// No joint went faster than its limit, nor accelerated harder (finite
    /// differences of the commanded path, 1 % for rounding).
    pub fn assert_within_limits(&self) {
        let dt = self.period();
        for (j, joint) in self.robot.joints().enumerate() {
            let q = self.joint(j, 0);
            let v: Vec<f64> = q.windows(2).map(|w| (w[1] - w[0]) / dt).collect();
            let a: Vec<f64> = v.windows(2).map(|w| (w[1] - w[0]) / dt).collect();
            let vmax = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let amax = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            assert!(
                vmax <= joint.max_velocity * 1.01,
                "{}: {vmax} deg/s",
                joint.name
            );
            assert!(
                amax <= joint.max_acceleration * 1.01,
                "{}: {amax} deg/s^2",
                joint.name
            );
        }
    }
}

/// The largest change of any joint's commanded angle over `cycles` (deg).
pub(super) fn spread(rows: &[Vec<f64>]) -> f64 {
    let n = rows.first().map_or(0, Vec::len);
    (0..n)
        .map(|j| {
            let (lo, hi) = rows.iter().fold((f64::MAX, f64::MIN), |(lo, hi), r| {
                (lo.min(r[j]), hi.max(r[j]))
            });
            hi - lo
        })
        .fold(0.0, f64::max)
}

/// The pan's index in the SO-101's joints.
pub(super) const PAN: usize = 0;
