//! Check a robot's servos with the doctor: every bus of the built-in
//! SO-101 on the built-in simulator (or on real servos with `--port`),
//! each finding printed with its severity, its servo and register, what is
//! wrong and what to do about it. Nothing is written: `CheckOptions { fix:
//! true, .. }` applies the fixes that are writes, then checks again.
//!
//! ```sh
//! cargo run -p servobus-robot --example doctor
//! cargo run -p servobus-robot --example doctor -- --port /dev/ttyACM0
//! ```
//!
//! Exit code: 0 when the doctor has run (whatever it found), 1 when it
//! could not, 2 for a bad command line.

use std::process::ExitCode;

use servobus_robot::doctor::{Advice, CheckOptions, Checkup};
use servobus_robot::{Error, Robot};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let ports: &[String] = match args.as_slice() {
        [] => &[], // no port: the robot file's, else the built-in simulator
        [flag, port] if flag == "--port" => std::slice::from_ref(port),
        _ => {
            eprintln!("usage: doctor [--port PORT]");
            return ExitCode::from(2);
        }
    };
    match check(ports) {
        Ok(checkup) => {
            print_checkup(&checkup);
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Opens the arm and checks its buses on `ports`.
fn check(ports: &[String]) -> Result<Checkup, Error> {
    let robot = Robot::open("so101")?;
    robot.doctor(ports, &CheckOptions::default())
}

/// Each bus, and each finding on it: severity, where, what, and the fix.
fn print_checkup(checkup: &Checkup) {
    for bus in &checkup.buses {
        let at = bus.at.port.as_deref().unwrap_or("the built-in simulator");
        let findings = bus.standing();
        let fixable = findings.iter().filter(|f| f.fixable()).count();
        println!(
            "bus `{}` on {at}: {} findings, {fixable} of them fixed by `fix: true`",
            bus.name,
            findings.len()
        );
        for finding in findings {
            let servo = finding
                .id
                .map_or("bus".to_owned(), |id| format!("servo {id}"));
            let register = finding
                .register
                .map(|r| format!(" ({r})"))
                .unwrap_or_default();
            let severity = finding.severity.to_string(); // padded below
            println!("{severity:<7} {servo}{register}: {}", finding.problem);
            match (&finding.advice, finding.advice.command()) {
                (Advice::None, _) => {}
                (_, Some(fix)) => println!("        fix: {fix:?}"),
                (advice, None) => println!("        to do: {advice:?}"),
            }
        }
    }
    for name in &checkup.unchecked {
        println!("bus `{name}`: not checked (no port)");
    }
}
