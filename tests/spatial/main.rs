//! Motion in space played through the real loop on the simulator, in
//! virtual time: the tool of `path: line` moves and the feet of a walk,
//! from forward kinematics of the simulator's true joint angles.

mod errors;
mod line;
mod log;
mod plan;
mod scrub;
mod walk;

use std::path::PathBuf;
use std::time::Duration;

use servobus_kinematics::Geometry;
use servobus_robot::sim::{new_truth, SimRobot};
use servobus_runtime::config::{load_motion, plan_motion};
use servobus_runtime::{Finish, RunOptions, VirtualRun};
use servobus_trajectory::JointState;

/// Runs `servobus ARGS`, which must succeed; its standard output.
fn servobus_ok(args: &[&std::ffi::OsStr]) -> Vec<u8> {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_servobus"))
        .args(args)
        .output()
        .expect("servobus runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// A file under the repository's `configs/`.
fn config(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(path)
}

/// What a played motion leaves: the robot's geometry (limits set), the
/// simulator's true angles (radians, robot order), one row per 10 ms, and
/// the planned angles at the same moments.
struct Played {
    model: Geometry,
    rows: Vec<Vec<f64>>,
    planned: Vec<Vec<f64>>,
}

/// Plays `name` (under `configs/motions/`) to its end in virtual time on a
/// simulator that starts at the motion's first pose.
fn play(name: &str) -> Played {
    let (motion, robot) = load_motion(&config(&format!("motions/{name}")), None).expect("loads");
    let path = plan_motion(&motion, &robot).expect("plans");
    let mut start = vec![JointState::default(); robot.joint_count()];
    path.sample(0.0, &mut start);
    let pose: Vec<f64> = start
        .iter()
        .map(|s| robot.units.from_rad(s.position))
        .collect();
    let truth = new_truth(&robot);
    let sim = SimRobot::builder(&robot)
        .pose(&pose)
        .truth(&truth)
        .build()
        .expect("simulates");
    let options = RunOptions {
        telemetry_capacity: 0,
        ..RunOptions::default()
    };
    let report = VirtualRun::new(&robot, path.clone(), sim.driver_buses(), options)
        .expect("starts")
        .run();
    assert_eq!(report.finish, Finish::Completed);
    sim.buses()[0].clock().advance(Duration::from_millis(500));
    sim.settle();
    let truth = truth.rows();
    let rows: Vec<Vec<f64>> = truth
        .iter()
        .map(|r| r.angles_deg.iter().map(|d| d.to_radians()).collect())
        .collect();
    // The path starts after the loop's start-up: the delay (to 10 ms) at
    // which the plan matches the truth best.
    let planned_at = |delay: f64| -> Vec<Vec<f64>> {
        let mut state = vec![JointState::default(); path.joints()];
        truth
            .iter()
            .map(|r| {
                path.sample(r.time_s - delay, &mut state);
                state.iter().map(|s| s.position).collect()
            })
            .collect()
    };
    let mismatch = |planned: &[Vec<f64>]| -> f64 {
        planned
            .iter()
            .zip(&rows)
            .map(|(p, r)| p.iter().zip(r).map(|(a, b)| (a - b).powi(2)).sum::<f64>())
            .sum()
    };
    let delay = (0..100)
        .map(|k| {
            let d = k as f64 * 0.01;
            (d, mismatch(&planned_at(d)))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0.0, |(d, _)| d);
    Played {
        model: robot.geometry().expect("the robot has geometry"),
        planned: planned_at(delay),
        rows,
    }
}
