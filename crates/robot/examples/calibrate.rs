//! Calibrate an arm through the procedure `servobus calibrate` runs, on the
//! built-in simulator: an SO-101 whose servo horns were fitted anywhere on
//! the turn (a random mounting), moved by a scripted hand instead of a
//! person (to the calibration pose, then each joint to one end stop, the
//! other and back). The steps end on their own when the arm is held still
//! (`auto`), as with `servobus calibrate --yes`. The calibration is written
//! to a file in the temporary directory, and the arm opened with it.
//!
//! ```sh
//! cargo run -p servobus-robot --example calibrate
//! ```

use std::process::ExitCode;
use std::time::Duration;

use servobus_robot::calibrate::{calibrate, LiveJoint, Operator, ProcedureOptions, Step};
use servobus_robot::config::{self, save_calibration, utc_now};
use servobus_robot::sim::{Hand, Mounting, SimRobot};
use servobus_robot::Robot;

/// The operator: says each step; never presses Enter (the hand is scripted).
struct Script;

impl Operator for Script {
    fn step(&mut self, step: Step) {
        println!("step: {step:?}");
    }
    fn watch(&mut self, _at: Duration, _joints: &[LiveJoint]) {}
    fn confirmed(&mut self) -> bool {
        false
    }
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The hand's script, degrees at seconds from the start: from rest to the
/// calibration pose by 1.5 s, then from 4.5 s each joint in turn to its
/// upper limit, its lower limit and back to the pose, 4 s a joint.
fn hand(arm: &config::Robot) -> Hand {
    let deg = |v: f64| arm.units.to_rad(v).to_degrees();
    let mut keys = Vec::new();
    for (j, (joint, &pose)) in arm.joints().zip(&arm.calibration_pose).enumerate() {
        let t = 4.5 + 4.0 * j as f64;
        let (pose, lo, hi) = (deg(pose), deg(joint.min), deg(joint.max));
        let sweep = [(1.0, hi), (1.2, hi), (2.7, lo), (2.9, lo), (3.9, pose)];
        let start = [(0.0, deg(joint.rest())), (1.5, pose), (t, pose)];
        let path = start.into_iter().chain(sweep.map(|(dt, a)| (t + dt, a)));
        keys.extend(path.map(|(at, a)| (at, vec![(j, a)])));
    }
    Hand::from_keyframes(arm, &keys)
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let robot = Robot::open("so101")?;
    let arm = robot.config();
    let sim = SimRobot::builder(arm)
        .mounting(Mounting::random(arm, 7)) // horns anywhere, stops 5 deg past the limits
        .hand(hand(arm))
        .build()?;
    // The procedure reads the servos on the buses' clock: virtual time here.
    let mut buses = sim.driver_buses();
    let options = ProcedureOptions {
        auto: true,
        taken: utc_now(),
        ..ProcedureOptions::default()
    };
    let calibration = calibrate(arm, &mut buses, &mut Script, &options)?;
    let file = std::env::temp_dir().join("so101-example.calibration.yaml");
    save_calibration(&calibration, &file)?;
    println!("wrote {}", file.display());
    // Opened with it, the arm's limits are the ranges measured, less a
    // margin at each end stop.
    let calibrated = Robot::options().calibration(&file).open("so101")?;
    for (joint, measured) in calibrated.config().joints().zip(&calibration.joints) {
        let (lo, hi) = measured.range_deg(joint.model);
        let seam = measured.crosses_seam().then_some("  (across the seam)");
        println!(
            "  {:<14} range {lo:7.1} .. {hi:5.1} deg  limits {:7.1} .. {:5.1}{}",
            joint.name,
            joint.min,
            joint.max,
            seam.unwrap_or("")
        );
    }
    Ok(())
}
