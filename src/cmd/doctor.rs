//! `servobus doctor`: checks every bus of a robot against its robot file and
//! the usual set-up mistakes, prints each finding with the command that
//! fixes it, and with `--fix` applies those fixes (EEPROM with
//! unlock-write-verify-lock; homing offsets for the session unless
//! `--write-servos`, which also stores what the robot file asks of the
//! servos' EEPROM: operating modes and `servo:` settings). The checks live
//! in [`servobus_robot::doctor`]; the text they are shown in, in
//! [`servobus::doctor`].

use std::process::ExitCode;

use servobus::doctor::{self, BusCheck, Finding, Shown};
use servobus_config::{load_robot, Robot, RobotOptions};
use servobus_robot::doctor::FixError;

use crate::shared::out::{errln, outln, StdoutError};

/// Arguments of `servobus doctor`.
#[derive(Debug, clap::Args)]
#[command(after_help = "\
Exit status (doctor's own):
  0  nothing wrong (information only)
  1  warnings only
  2  errors found, or doctor could not finish (the port failed mid-check,
     or SIGINT, SIGTERM or SIGHUP stopped --fix: the fix under way is
     finished first, the ones after it are listed as not applied),
     or a usage or input error (command line, robot file, port)")]
pub struct Args {
    /// The robot to check the buses against, its port and the calibration
    /// to check the servos against.
    #[command(flatten)]
    pub robot: crate::shared::flags::RobotArgs,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Apply the fixes that are writes (EEPROM with unlock-write-verify-lock),
    /// then check again. Homing offsets are set for this session only, as
    /// play sets them (lost at power-off).
    #[arg(long)]
    pub fix: bool,
    /// With --fix: store homing offsets in the servos' EEPROM instead, and
    /// store what the robot file asks of their EEPROM (each joint's
    /// operating mode, with the torque off; its `servo:` p, d, i,
    /// protection_current and max_temperature).
    #[arg(long, requires = "fix")]
    pub write_servos: bool,
}

/// Exit status when doctor could not finish its checks: as for errors
/// found, since nothing can be said about what was not checked.
const UNFINISHED: u8 = 2;

/// Runs `servobus doctor`: its exit status is its own (see `--help`), 2
/// also when it could not finish.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    match examine_robot(&args) {
        Ok(code) => Ok(code),
        Err(e) => {
            crate::shared::exit::report(&e);
            Ok(ExitCode::from(UNFINISHED))
        }
    }
}

fn examine_robot(args: &Args) -> anyhow::Result<ExitCode> {
    let robot = load_robot(
        &args.robot.path,
        &RobotOptions::default()
            .calibration(args.robot.hardware.calibration.as_deref())
            .any_rate(),
    )?;
    if args.fix {
        // A signal during a fix is acted on once the servo is locked again;
        // the fixes applied and the ones not begun are then said.
        if let Err(e) = servobus_robot::bus::catch_stop_signals() {
            errln!("warning: a signal will end doctor without a report ({e})");
        }
    }
    let options = doctor::CheckOptions {
        fix: args.fix,
        write_servos: args.write_servos,
    };
    let checkup = doctor::check(&robot, args.robot.hardware.port.as_slice(), &options).map_err(
        |e| match e {
            // A port that cannot be opened is an input error, said as the
            // other commands say it.
            servobus_robot::Error::Open(e) => anyhow::Error::from(e),
            e => e.into(),
        },
    )?;
    for bus in &checkup.unchecked {
        errln!("warning: bus `{bus}` has no port: not checked");
    }
    let standing = checkup.standing();
    let stopped = servobus_robot::bus::stop_signal();
    let status = match stopped {
        Some(_) => UNFINISHED,
        None => doctor::exit_status(&standing),
    };
    if args.json {
        print_json(&robot, &checkup.buses, status)?;
    } else {
        print_text(&robot, &checkup.buses, &standing, args)?;
    }
    if let Some(signal) = stopped {
        errln!(
            "stopped by {signal}: the fixes said `fixed` were applied (each EEPROM write \
             unlocked, written, verified and locked); those `not applied` were not begun"
        );
    }
    Ok(ExitCode::from(status))
}

/// Prints `findings` (in the order a new robot needs them) under the
/// heading of each step.
fn print_findings(findings: &[Finding]) -> Result<(), StdoutError> {
    let mut step = None;
    for f in findings {
        if step != Some(f.step) {
            step = Some(f.step);
            outln!("{}", doctor::heading(f.step))?;
        }
        let who = match (f.id, f.register) {
            (Some(id), Some(r)) => format!("servo {id} {r}"),
            (Some(id), None) => format!("servo {id}"),
            (None, Some(r)) => r.to_string(),
            (None, None) => format!("bus `{}`", f.bus),
        };
        outln!(
            "{:<8} {who}: {}",
            f.severity.to_string().to_uppercase(),
            f.problem
        )?;
        let fix = f.fix_text();
        if !fix.is_empty() {
            let mark = f.fix_flags().map(|flags| format!(" [{flags}]"));
            outln!("         fix{}: {fix}", mark.unwrap_or_default())?;
        }
    }
    Ok(())
}

fn print_text(
    robot: &Robot,
    outcomes: &[BusCheck],
    standing: &[Finding],
    args: &Args,
) -> Result<(), StdoutError> {
    for o in outcomes {
        let port = o.at.port.as_deref().unwrap_or("the built-in simulator");
        outln!(
            "{} bus `{}` on {port} at {} baud: {} of {} servos read",
            robot.name,
            o.name,
            o.at.baud,
            o.first.servos.len(),
            o.first.expected
        )?;
        print_findings(&o.first.findings)?;
        for fx in &o.fixes {
            let done = doctor::applied_text(&fx.applied);
            match &fx.result {
                Ok(()) => outln!("fixed    servo {}: {done}", fx.id)?,
                Err(e @ FixError::Stopped(_)) => outln!("NOT DONE servo {}: {done} ({e})", fx.id)?,
                Err(e) => outln!("FAILED   servo {}: {done} ({e})", fx.id)?,
            }
        }
        if args.fix && !args.write_servos {
            for f in o.first.findings.iter().filter(|f| f.needs_write_servos()) {
                let id = f.id.map_or_else(String::new, |id| format!("servo {id}: "));
                outln!(
                    "skipped  {id}only an EEPROM write fixes this: give --fix --write-servos \
                     to store it"
                )?;
            }
        }
        if let Some(after) = &o.after {
            outln!("after the fixes:")?;
            print_findings(&after.findings)?;
        }
    }
    let count = |s| standing.iter().filter(|f| f.severity == s).count();
    // What is wrong and can be fixed; an INFO needs nothing before play.
    let to_fix = |eeprom: bool| {
        standing
            .iter()
            .filter(|f| f.severity > doctor::Severity::Info && f.fixable())
            .filter(|f| f.needs_write_servos() == eeprom)
            .count()
    };
    let (plain, eeprom) = (to_fix(false), to_fix(true));
    let mut hint = String::new();
    if plain > 0 && !args.fix {
        hint += &format!("; {plain} can be fixed with --fix");
    }
    if eeprom > 0 && !(args.fix && args.write_servos) {
        hint += &format!("; {eeprom} with --fix --write-servos (EEPROM)");
    }
    outln!(
        "{} error(s), {} warning(s){hint}",
        count(doctor::Severity::Error),
        count(doctor::Severity::Warning)
    )?;
    Ok(())
}

fn print_json(robot: &Robot, outcomes: &[BusCheck], status: u8) -> anyhow::Result<()> {
    let json_findings = |fs: &[Finding]| -> Vec<serde_json::Value> {
        fs.iter()
            .map(|f| {
                let mut v = serde_json::to_value(f).unwrap_or_default();
                v["fixable"] = f.fixable().into();
                v["fix_flags"] = f.fix_flags().into();
                v["fix"] = f.fix_text().into();
                v["command"] = f.command_line().into();
                // What the robot file asks of the register, beside what the
                // servo holds (null for other findings).
                v["setting"] = serde_json::to_value(&f.setting).unwrap_or_default();
                v
            })
            .collect()
    };
    let buses: Vec<_> = outcomes
        .iter()
        .map(|o| {
            let fixes: Vec<_> = o
                .fixes
                .iter()
                .map(|fx| {
                    serde_json::json!({
                        "id": fx.id,
                        "command": doctor::applied_text(&fx.applied),
                        "ok": fx.result.is_ok(),
                        "error": fx.result.as_ref().err().map(ToString::to_string),
                    })
                })
                .collect();
            serde_json::json!({
                "name": o.name,
                "port": o.at.port,
                "baud": o.at.baud,
                "expected": o.first.expected,
                "read": o.first.servos.iter().map(|s| s.id).collect::<Vec<_>>(),
                "findings": json_findings(&o.first.findings),
                "fixes": fixes,
                "after_fix": o.after.as_ref().map(|a| json_findings(&a.findings)),
            })
        })
        .collect();
    let out = serde_json::json!({
        "robot": robot.name,
        "buses": buses,
        "exit": status,
    });
    outln!("{}", crate::shared::json::line(&out)?)?;
    Ok(())
}
