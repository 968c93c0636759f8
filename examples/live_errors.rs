//! Read the telemetry channel to print tracking errors while a motion plays.
//!
//! The run happens on its own thread; this thread reads what the control
//! loop publishes every cycle. The loop never waits for this reader: were it
//! too slow, samples would be dropped (and counted in the report).
//!
//! ```sh
//! cargo run --example live_errors -- configs/motions/arm-pick-place.yaml
//! ```

use std::path::PathBuf;

use servobus_runtime::config::{load_motion, plan_motion};
use servobus_runtime::{spawn_virtual, RunOptions, Telemetry};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).map_or_else(
        || PathBuf::from("configs/motions/arm-pick-place.yaml"),
        PathBuf::from,
    );
    let (motion, robot) = load_motion(&path, None)?;
    let trajectory = plan_motion(&motion, &robot)?;

    let buses = servobus_runtime::sim::virtual_buses(&robot)?;
    let options = RunOptions {
        units: Some(motion.units),
        ..RunOptions::default()
    };
    let runner = spawn_virtual(&robot, trajectory, buses, options)?;

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
            Telemetry::Finished(how) => println!("finished: {how:?}"),
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
