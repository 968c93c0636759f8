//! Playing a motion on a calibrated (or not) simulated robot and comparing
//! the body's physical angles with the motion's keyframes.
#![allow(dead_code)]

use std::path::Path;

use servobus_driver::Bus;
use servobus_robot::calibrate::ProcedureOptions;
use servobus_runtime::config::{load_motion_calibrated, plan_motion, Robot};
use servobus_runtime::{Finish, RunOptions, Telemetry, VirtualRun};
use servobus_sim::SimBus;

/// What playing a motion did to the body.
pub struct Played {
    /// How the run ended.
    pub finish: Option<Finish>,
    /// Keyframes the path reached.
    pub reached: usize,
    /// Keyframes in the motion.
    pub keyframes: usize,
    /// The largest miss, degrees, between the body's physical angles and
    /// the keyframe, at every cycle where the path is at a keyframe.
    pub worst: f64,
}

/// The options of `servobus calibrate` for a test: with `auto`, a step
/// ends once the joints are still; without it, when Enter is pressed.
pub fn procedure(auto: bool) -> ProcedureOptions {
    ProcedureOptions {
        auto,
        taken: "test".into(),
        ..ProcedureOptions::default()
    }
}

/// Checks that an uncalibrated robot, whose readings are off by up to
/// `misread` degrees, did not play its motion: it stopped on a fault with
/// at most `reached_at_most` keyframes reached, or missed by over 20 deg.
pub fn assert_uncalibrated_fails(played: &Played, misread: f64, reached_at_most: usize) {
    let Played {
        finish,
        reached,
        keyframes,
        worst,
    } = played;
    println!(
        "uncalibrated: readings off by up to {misread:.1} deg; {finish:?}, {reached} of {keyframes} keyframes, worst miss {worst:.1} deg"
    );
    let refused = *finish == Some(Finish::Fault) && *reached <= reached_at_most;
    assert!(
        refused || *worst > 20.0,
        "uncalibrated arm played within {worst:.1} deg"
    );
}

/// Plays `motion` (a path) for `robot` (its file at `robot_path`, with the
/// calibration `cal` or the file's own) on `buses`; `truth` gives the
/// body's physical angles, degrees, in the robot's joint order.
pub fn play(
    motion: &Path,
    robot_path: &Path,
    robot: &Robot,
    cal: Option<&Path>,
    buses: Vec<Bus<SimBus>>,
    truth: impl Fn() -> Vec<f64>,
) -> Played {
    let (motion, loaded) =
        load_motion_calibrated(motion, Some(robot_path), cal).expect("motion loads");
    assert_eq!(
        loaded.calibration, robot.calibration,
        "the robot tested is the one played"
    );
    let traj = plan_motion(&motion, &loaded).expect("plans");
    let options = RunOptions {
        units: Some(motion.units),
        ..RunOptions::default()
    };
    let mut run = VirtualRun::new(&loaded, traj, buses, options).expect("starts");
    let rx = run.telemetry();
    let mut planned = vec![f64::NAN; loaded.joint_count()];
    let mut worst: f64 = 0.0;
    let mut hits = vec![0usize; motion.keyframes.len()];
    for _ in 0..500_000 {
        let going = run.step();
        while let Ok(msg) = rx.try_recv() {
            if let Telemetry::Cycle(c) = msg {
                for j in c.joints() {
                    planned[j.joint] = j.planned;
                }
            }
        }
        let body = truth();
        for (k, kf) in motion.keyframes.iter().enumerate() {
            let at_kf = planned
                .iter()
                .zip(&kf.positions)
                .all(|(p, q)| (p - q).abs() < 0.2);
            if at_kf {
                hits[k] += 1;
                for (b, q) in body.iter().zip(&kf.positions) {
                    worst = worst.max((b - q).abs());
                }
            }
        }
        if !going {
            break;
        }
    }
    Played {
        finish: run.finished(),
        reached: hits.iter().filter(|&&h| h > 0).count(),
        keyframes: hits.len(),
        worst,
    }
}
