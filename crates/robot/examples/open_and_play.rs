//! Open a robot, load a motion, connect, play it to its end and print the
//! report: the built-in SO-101 (`so101`) playing the built-in `arm-wave`,
//! on the built-in simulator in virtual time, or on real servos (or a
//! `servobus sim` pty) with `--port`.
//!
//! ```sh
//! cargo run -p servobus-robot --example open_and_play
//! cargo run -p servobus-robot --example open_and_play -- --port /dev/ttyACM0
//! ```

use std::process::ExitCode;

use servobus_robot::{Error, Finish, Report, Robot, Target};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let target = match args.as_slice() {
        [] => Target::VirtualSimulator,
        [flag, port] if flag == "--port" => Target::Ports(vec![port.clone()]),
        _ => {
            eprintln!("usage: open_and_play [--port PORT]");
            return ExitCode::from(2);
        }
    };
    match play(target) {
        Ok(report) if report.finish == Finish::Completed => {
            print_report(&report);
            ExitCode::SUCCESS
        }
        Ok(report) => {
            print_report(&report);
            eprintln!("the motion did not play to its end: {:?}", report.finish);
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Opens the arm and its motion, connects to `target`, plays to the end.
fn play(target: Target) -> Result<Report, Error> {
    let robot = Robot::open("so101")?; // a built-in name, or a robot file
    let motion = robot.motion("arm-wave")?; // likewise
    let seconds = robot.plan(&motion)?.duration();
    println!("arm-wave on {}: {seconds:.2} s planned", robot.name());
    // On real servos the calibration is checked here, before anything moves.
    let connection = robot.connect(target)?;
    for slow in connection.slow_adapters() {
        eprintln!("warning: {slow}");
    }
    let options = connection.options(); // the robot's defaults, as `servobus play`
    let run = connection.play(&motion, options)?;
    run.join() // waits for the end; `run.stop()` from another thread ends it early
}

/// The report's figures: how the loop kept time, and how each joint
/// followed the path.
fn print_report(report: &Report) {
    println!(
        "{:?} after {} cycles at {:.1} Hz ({:.2} s); {} timeouts, {} retries, {} overruns",
        report.finish,
        report.cycles,
        report.achieved_rate_hz,
        report.duration_s,
        report.timeouts,
        report.retries,
        report.overruns
    );
    println!(
        "lead {:.1} ms; tracking error ({}):",
        report.lead_ms, report.units
    );
    for joint in &report.joints {
        println!(
            "  {:<14} rms {:.3}  max {:.3}",
            joint.name, joint.rms_error, joint.max_error
        );
    }
}
