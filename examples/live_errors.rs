//! Read the telemetry channel to print tracking errors while a motion plays.
//!
//! The run happens on its own thread; this thread reads what the control
//! loop publishes every cycle. The loop never waits for this reader: were it
//! too slow, samples would be dropped (and counted in the report).
//!
//! ```sh
//! cargo run --example live_errors -- configs/motions/arm-pick-place.yaml
//! ```

use std::path::Path;
use std::process::ExitCode;

mod common;

use common::Outcome;
use servobus_runtime::config::{load_motion, plan_motion};
use servobus_runtime::{Finish, RunOptions, Telemetry, VirtualRun};

const USAGE: &str = "usage: live_errors [MOTION]\n\
    Plays MOTION (a motion file or a built-in name; default arm-pick-place) on\n\
    the simulated robot and prints each joint's tracking error every 50 cycles.";

fn main() -> ExitCode {
    common::run_motion(USAGE, "arm-pick-place", watch)
}

fn watch(_arg: &str, path: &Path) -> Outcome {
    let (motion, robot) = load_motion(path, None)?;
    let trajectory = plan_motion(&motion, &robot)?;

    let buses = servobus_robot::sim::virtual_buses(&robot)?;
    let options = RunOptions {
        units: Some(motion.units),
        ..RunOptions::default()
    };
    let runner = VirtualRun::new(&robot, trajectory, buses, options)?.spawn()?;

    let names: Vec<String> = robot.joints().map(|j| j.name.clone()).collect();
    for message in runner.telemetry() {
        match message {
            // Every 50th cycle: each joint's error, planned minus measured.
            Telemetry::Cycle(sample) if sample.cycle % 50 == 0 => {
                let errors: Vec<String> = sample
                    .joints()
                    .iter()
                    .map(|j| format!("{} {:+.2}", names[j.joint], j.error))
                    .collect();
                println!("t = {:5.2} s  {}", sample.time_s, errors.join("  "));
            }
            Telemetry::Fault(fault) => println!("fault: {fault}"),
            Telemetry::Finished(how) => println!("{}", finished(how)),
            _ => {}
        }
    }
    let report = runner.join()?;
    println!(
        "worst max error {:.2} {}, {} telemetry samples dropped",
        report.worst_max_error(),
        report.units,
        report.telemetry_dropped
    );
    Ok(())
}

/// How the run ended, as a sentence.
fn finished(how: Finish) -> &'static str {
    match how {
        Finish::Completed => "the motion played to its end",
        Finish::Stopped => "stopped on request",
        Finish::TorqueOff => "ended by turning the torque off",
        Finish::Fault => "ended by a fault (see above)",
        Finish::Abandoned => "abandoned: nobody asked it to play",
        _ => "ended",
    }
}
