//! Play a motion file on a robot through the facade library
//! (`servobus-robot`): on real servos or a `servobus sim` pty with
//! `--port`, otherwise on the built-in simulator in virtual time.
//!
//! ```sh
//! cargo run --release --example play_motion -- configs/motions/arm-wave.yaml --port /dev/ttyACM0
//! cargo run --release --example play_motion -- hexapod-dance   # a built-in name, simulated
//! ```
//!
//! Exit code: 0 when the motion played to its end, 1 when it did not or
//! could not start (the error said in words), 2 for a bad command line.

use std::process::ExitCode;

use servobus_robot::{Error, Finish, Motion, Report, Robot, Target};

const USAGE: &str = "usage: play_motion [MOTION] [--port PORT]\n\
    Plays MOTION (a motion file or a built-in name; default arm-wave) on the\n\
    robot it names: on PORT (real servos or `servobus sim`), else on the\n\
    built-in simulator in virtual time. Prints the run's report.";

fn main() -> ExitCode {
    if std::env::args().any(|a| a == "--help" || a == "-h") {
        println!("{USAGE}");
        return ExitCode::SUCCESS;
    }
    let Some((motion, target)) = parse(std::env::args().skip(1)) else {
        eprintln!("{USAGE}");
        return ExitCode::from(2);
    };
    match play(&motion, target) {
        Ok(report) => {
            print_report(&report);
            ExitCode::from(u8::from(report.finish != Finish::Completed))
        }
        Err(e) => {
            eprintln!("error: {}", said(&e));
            ExitCode::FAILURE
        }
    }
}

/// Opens the motion and its robot, connects, plays to the end.
fn play(motion: &str, target: Target) -> Result<Report, Error> {
    let (robot, motion) = Robot::of_motion(motion)?;
    let seconds = robot.plan(&motion)?.duration();
    println!(
        "{} on {}: {seconds:.2} s",
        motion_name(&motion),
        robot.name()
    );
    let connection = robot.connect(target)?;
    for slow in connection.slow_adapters() {
        eprintln!("warning: {slow}");
    }
    let options = connection.options();
    connection.play(&motion, options)?.join()
}

/// MOTION and `--port PORT` in any order; `None` for a bad command line.
fn parse(mut args: impl Iterator<Item = String>) -> Option<(String, Target)> {
    let (mut motion, mut target) = (None, Target::VirtualSimulator);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--port" => target = Target::Ports(vec![args.next()?]),
            a if a.starts_with('-') || motion.is_some() => return None,
            _ => motion = Some(arg),
        }
    }
    Some((motion.unwrap_or_else(|| "arm-wave".into()), target))
}

/// `e` and its causes, each said once.
fn said(e: &Error) -> String {
    let mut text = e.to_string();
    let mut cause = std::error::Error::source(e);
    while let Some(c) = cause {
        let said = c.to_string();
        let part = said.strip_prefix("I/O error: ").unwrap_or(&said);
        // A cause that begins by repeating the end of the text adds the rest.
        let repeated = part
            .match_indices(": ")
            .map(|(i, _)| i)
            .find(|&i| text.ends_with(&part[..i]));
        match repeated {
            _ if text.contains(part) => {}
            Some(i) => text.push_str(&part[i..]),
            None => text = format!("{text}: {part}"),
        }
        cause = c.source();
    }
    text
}

/// The motion's file name without `.yaml` (`arm-wave`).
fn motion_name(motion: &Motion) -> String {
    let stem = motion.path.file_stem().unwrap_or(motion.path.as_os_str());
    stem.to_string_lossy().into_owned()
}

fn print_report(report: &Report) {
    let finish = match report.finish {
        Finish::Completed => "played to its end",
        Finish::Stopped => "stopped",
        Finish::TorqueOff => "ended with the torque off",
        Finish::Fault => "ended by a fault",
        _ => "abandoned",
    };
    println!(
        "{finish} after {} cycles at {:.1} Hz ({:.2} s); {} timeouts, {} retries, {} overruns",
        report.cycles,
        report.achieved_rate_hz,
        report.duration_s,
        report.timeouts,
        report.retries,
        report.overruns
    );
    println!("tracking error ({}):", report.units);
    for joint in &report.joints {
        println!(
            "  {:<14} rms {:.3}  max {:.3} {}",
            joint.name, joint.rms_error, joint.max_error, report.units
        );
    }
}
