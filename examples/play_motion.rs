//! Play a motion file on the simulated SO-101 arm from library code.
//!
//! The same steps as `servobus play --fast`: load and validate the motion
//! and its robot, plan the path, build one simulated bus per robot bus in
//! virtual time, run, and print the report.
//!
//! ```sh
//! cargo run --example play_motion -- configs/motions/arm-wave.yaml
//! cargo run --example play_motion -- hexapod-dance   # a built-in name
//! ```

use std::path::Path;
use std::process::ExitCode;

mod common;

use common::Outcome;
use servobus_runtime::config::{load_motion, plan_motion};
use servobus_runtime::{RunOptions, VirtualRun};

const USAGE: &str = "usage: play_motion [MOTION]\n\
    Plays MOTION (a motion file or a built-in name; default arm-wave) on the\n\
    simulated robot in virtual time and prints the tracking errors.";

fn main() -> ExitCode {
    common::run_motion(USAGE, "arm-wave", play)
}

fn play(arg: &str, path: &Path) -> Outcome {
    // Every error names the file, line and column; nothing moves before both
    // files are valid.
    let (motion, robot) = load_motion(path, None)?;
    let path_plan = plan_motion(&motion, &robot)?;
    println!("{arg} on {}: {:.2} s", robot.name, path_plan.duration());

    // One simulated bus per robot bus, each servo at its joint's rest
    // position. Each bus has its own virtual clock: the runtime moves them
    // in step.
    let buses = servobus_runtime::sim::virtual_buses(&robot)?;

    let options = RunOptions {
        units: Some(motion.units),
        rate_hz: Some(motion.rate_hz(&robot)),
        ..RunOptions::default()
    };
    let report = VirtualRun::new(&robot, path_plan, buses, options)?.run();

    println!(
        "{} cycles at {:.1} Hz; tracking error ({}):",
        report.cycles, report.achieved_rate_hz, report.units
    );
    for joint in &report.joints {
        println!(
            "  {:<14} rms {:.3}  max {:.3} {}",
            joint.name, joint.rms_error, joint.max_error, report.units
        );
    }
    Ok(())
}
