//! Build a trajectory in code and stream it to the simulated arm.
//!
//! No motion file: the keyframes are written here, in radians, one value per
//! joint of the robot in its joint order. The first move is as fast as the
//! joint limits allow; the second arrives exactly at t = 3 s.
//!
//! ```sh
//! cargo run --example stream_trajectory
//! ```

use servobus_robot::sim::SimRobot;
use servobus_runtime::config::{joint_limits, load_robot, RobotOptions};
use servobus_runtime::{RunOptions, VirtualRun};
use servobus_trajectory::{plan, Keyframe, PlanOptions};

fn main() -> std::process::ExitCode {
    // Errors print in words (`error: ...`), not in their `Debug` form.
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let robot = load_robot(
        &servobus::builtin::robot_path_or_name("so101".as_ref()),
        &RobotOptions::default(),
    )?;
    let deg = |d: f64| d.to_radians();

    // shoulder_pan, shoulder_lift, elbow_flex, wrist_flex, wrist_roll, gripper
    let start = [0.0, deg(-90.0), deg(90.0), deg(45.0), 0.0, deg(10.0)];
    let reach = [
        deg(45.0),
        deg(-30.0),
        deg(20.0),
        deg(-10.0),
        deg(60.0),
        deg(60.0),
    ];
    let keyframes = [
        Keyframe::new(start),
        Keyframe::new(reach),
        Keyframe::new(start).at(3.0),
    ];
    let path = plan(&joint_limits(&robot), &keyframes, &PlanOptions::default())?;
    println!("path of {:.3} s", path.duration());

    // The simulated arm, its servos at the start pose (the robot file's
    // mapping turns the angles into ticks, offsets and inversions included).
    let pose: Vec<f64> = start.iter().map(|&a| robot.units.from_rad(a)).collect();
    let sim = SimRobot::builder(&robot).pose(&pose).build()?;

    let options = RunOptions {
        rate_hz: Some(250.0),
        ..RunOptions::default()
    };
    let report = VirtualRun::new(&robot, path, sim.driver_buses(), options)?.run();
    println!(
        "{} cycles at {:.0} Hz, worst RMS tracking error {:.3} {}",
        report.cycles,
        report.achieved_rate_hz,
        report.worst_rms_error(),
        report.units
    );
    // The servos really moved: the wrist is back where it started.
    match sim.buses()[0].present_position(5) {
        Some(tick) => println!("wrist_roll servo (ID 5) ends at tick {tick}"),
        None => println!("wrist_roll servo (ID 5) is not on the bus"),
    }
    Ok(())
}
