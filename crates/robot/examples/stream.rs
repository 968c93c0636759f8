//! Stream targets to a live run: the SO-101's shoulder pan swung out and
//! back for three seconds, one target every 20 ms (as a policy or a leader
//! arm sends them), then an action chunk (a second of timed points) brings
//! it to the other side, then a stop; the report says how the run kept to
//! the targets. On the built-in simulator paced by the wall clock
//! (`Target::Ports` for real servos starts the same way).
//!
//! ```sh
//! cargo run -p servobus-robot --example stream
//! ```

use std::f64::consts::PI;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use servobus_robot::{Chunk, LiveTarget, Report, Robot, RunOptions, Target};

/// The joint moved.
const JOINT: &str = "shoulder_pan";
/// The time between two targets.
const EVERY: Duration = Duration::from_millis(20);

fn main() -> ExitCode {
    match stream() {
        Ok(report) => {
            print_report(&report);
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Connects, streams the targets and the chunk, stops; the run's report.
fn stream() -> Result<Report, Box<dyn std::error::Error>> {
    let robot = Robot::open("so101")?;
    let connection = robot.connect(Target::Simulator)?;
    let options = RunOptions {
        approach: None,                    // live targets start from where the joints are
        units: Some(robot.config().units), // the report in the robot file's degrees
        ..connection.options()
    };
    let run = connection.live(options)?;
    let targets = run.targets();
    let start = Instant::now();
    // 0 -> 40 deg -> 0 along a raised cosine over 3 s; targets are radians.
    while start.elapsed() < Duration::from_secs(3) {
        let t = start.elapsed().as_secs_f64();
        let deg = 20.0 * (1.0 - (2.0 * PI * t / 3.0).cos());
        targets.send(LiveTarget::named(t, vec![(JOINT.into(), deg.to_radians())]))?;
        std::thread::sleep(EVERY);
    }
    // A chunk: 50 points 20 ms apart from its arrival, 0 -> -30 deg eased.
    let points = (0..50)
        .map(|k| (-15.0 * (1.0 - (PI * f64::from(k) / 49.0).cos())).to_radians())
        .collect();
    targets.send_chunk(Chunk::named(None, 0.02, vec![(JOINT.into(), points)]))?;
    // Stop once it has played (before the target timeout would stop it).
    std::thread::sleep(Duration::from_millis(1100));
    run.stop()?;
    Ok(run.join()?)
}

/// How the run kept time, and how the joint kept to its targets.
fn print_report(report: &Report) {
    let u = report.units;
    println!(
        "{:?} after {} cycles at {:.1} Hz ({:.2} s)",
        report.finish, report.cycles, report.achieved_rate_hz, report.duration_s
    );
    if let Some(live) = &report.live {
        println!(
            "targets: {} received, {} clamped, {} refused, {} timeouts",
            live.received, live.clamped, live.refused, live.timeouts
        );
        // How far the commanded path went past the targets of the last 0.5 s.
        if let Some(j) = live.envelope.iter().find(|j| j.name == JOINT) {
            let (over, allowed) = (j.overshoot, j.allowance);
            println!("{JOINT}: {over:.2} {u} past its targets ({allowed:.2} {u} unavoidable)");
        }
    }
    if let Some(j) = report.joints.iter().find(|j| j.name == JOINT) {
        let (rms, max) = (j.rms_error, j.max_error);
        println!("{JOINT}: tracking error rms {rms:.3} {u}, max {max:.3} {u}");
    }
}
