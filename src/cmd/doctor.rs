//! `servobus doctor`: checks every bus of a robot against its robot file and
//! the usual set-up mistakes, prints each finding with the command that
//! fixes it, and with `--fix` applies those fixes (EEPROM with
//! unlock-write-verify-lock; homing offsets for the session unless
//! `--write-servos`). The checks live in [`servobus::doctor`].

use std::process::ExitCode;

use anyhow::Context;
use servobus::doctor::{self, Examined, Finding, FixOutcome, Fixing, PortKind, Target};
use servobus_driver::{Bus, Clock, Transport};
use servobus_runtime::config::{load_robot, Robot, RobotOptions};

use super::link::{bus_ports, open_bus_quietly, Allowance};

/// Arguments of `servobus doctor`.
#[derive(Debug, clap::Args)]
#[command(after_help = "\
Exit status (doctor's own):
  0  nothing wrong (information only)
  1  warnings only
  2  errors found, or doctor could not finish (the port failed mid-check),
     or a usage or input error (command line, robot file, port)")]
pub struct Args {
    /// The robot to check the buses against, its port and the calibration
    /// to check the servos against.
    #[command(flatten)]
    pub robot: super::RobotArgs,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Apply the fixes that are writes (EEPROM with unlock-write-verify-lock),
    /// then check again. Homing offsets are set for this session only, as
    /// play sets them (lost at power-off).
    #[arg(long)]
    pub fix: bool,
    /// With --fix: store homing offsets in the servos' EEPROM instead.
    #[arg(long, requires = "fix")]
    pub write_servos: bool,
}

/// What was found on one bus.
struct BusOutcome {
    name: String,
    target: Target,
    first: Examined,
    fixes: Vec<FixOutcome>,
    after: Option<Examined>,
}

impl BusOutcome {
    /// The findings that stand: after the fixes when there were any.
    fn standing(&self) -> &[Finding] {
        self.after
            .as_ref()
            .unwrap_or(&self.first)
            .findings
            .as_slice()
    }
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
            super::exit::report(&e);
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
    let ports = bus_ports(&robot, args.robot.hardware.port.as_slice());
    let mut outcomes = Vec::new();
    if ports.iter().all(Option::is_none) {
        let buses = servobus_runtime::sim::virtual_buses(&robot)?;
        for (index, (mut bus, cfg)) in buses.into_iter().zip(&robot.buses).enumerate() {
            let target = Target {
                port: None,
                baud: cfg.baud,
            };
            let kind = PortKind::Simulator;
            outcomes.push(check(&mut bus, (&robot, index), target, &kind, args)?);
        }
    } else {
        for (index, (cfg, port)) in robot.buses.iter().zip(ports).enumerate() {
            let Some(port) = port else {
                eprintln!("warning: bus `{}` has no port: not checked", cfg.name);
                continue;
            };
            // A slow adapter is one of the findings: no warning besides.
            let mut bus = open_bus_quietly(cfg, &port, Allowance::Assumed)?;
            let kind = PortKind::of(bus.transport());
            let target = Target {
                port: Some(port),
                baud: cfg.baud,
            };
            outcomes.push(check(&mut bus, (&robot, index), target, &kind, args)?);
        }
    }
    let standing: Vec<Finding> = outcomes
        .iter()
        .flat_map(|o| o.standing().iter().cloned())
        .collect();
    let status = doctor::exit_status(&standing);
    if args.json {
        print_json(&robot, &outcomes, status)?;
    } else {
        print_text(&robot, &outcomes, &standing, args.fix);
    }
    Ok(ExitCode::from(status))
}

/// Examines the robot's bus `index` through `bus` and, with `--fix`,
/// applies the fixes and examines it again.
fn check<T: Transport, C: Clock>(
    bus: &mut Bus<T, C>,
    (robot, index): (&Robot, usize),
    target: Target,
    kind: &PortKind,
    args: &Args,
) -> anyhow::Result<BusOutcome> {
    let cfg = robot
        .buses
        .get(index)
        .with_context(|| format!("the robot has no bus {index}"))?;
    let context = || format!("bus `{}`: doctor could not finish", cfg.name);
    let first = doctor::examine(bus, robot, cfg, &target, kind).with_context(context)?;
    let mut fixes = Vec::new();
    let mut after = None;
    let how = Fixing {
        robot,
        bus: index,
        write_servos: args.write_servos,
    };
    if args.fix && first.findings.iter().any(Finding::fixable) {
        fixes = doctor::apply(bus, &first.findings, &how).with_context(context)?;
        after = Some(doctor::examine(bus, robot, cfg, &target, kind).with_context(context)?);
    }
    Ok(BusOutcome {
        name: cfg.name.clone(),
        target,
        first,
        fixes,
        after,
    })
}

/// Prints `findings` (in the order a new robot needs them) under the
/// heading of each step.
fn print_findings(findings: &[Finding]) {
    let mut step = None;
    for f in findings {
        if step != Some(f.step) {
            step = Some(f.step);
            println!("{}", f.step.heading());
        }
        let who = match (f.id, f.register) {
            (Some(id), Some(r)) => format!("servo {id} {r}"),
            (Some(id), None) => format!("servo {id}"),
            (None, Some(r)) => r.to_string(),
            (None, None) => format!("bus `{}`", f.bus),
        };
        println!(
            "{:<8} {who}: {}",
            f.severity.to_string().to_uppercase(),
            f.problem
        );
        if !f.fix.is_empty() {
            let mark = if f.fixable() { " [--fix]" } else { "" };
            println!("         fix{mark}: {}", f.fix);
        }
    }
}

fn print_text(robot: &Robot, outcomes: &[BusOutcome], standing: &[Finding], fixed: bool) {
    for o in outcomes {
        let port = o.target.port.as_deref().unwrap_or("the built-in simulator");
        println!(
            "{} bus `{}` on {port} at {} baud: {} of {} servos read",
            robot.name,
            o.name,
            o.target.baud,
            o.first.servos.len(),
            o.first.expected
        );
        print_findings(&o.first.findings);
        for fx in &o.fixes {
            match &fx.result {
                Ok(()) => println!("fixed    servo {}: {}", fx.id, fx.command),
                Err(e) => println!("FAILED   servo {}: {} ({e})", fx.id, fx.command),
            }
        }
        if let Some(after) = &o.after {
            println!("after the fixes:");
            print_findings(&after.findings);
        }
    }
    let count = |s| standing.iter().filter(|f| f.severity == s).count();
    let fixable = standing.iter().filter(|f| f.fixable()).count();
    let hint = if fixable > 0 && !fixed {
        format!("; {fixable} can be fixed with --fix")
    } else {
        String::new()
    };
    println!(
        "{} error(s), {} warning(s){hint}",
        count(doctor::Severity::Error),
        count(doctor::Severity::Warning)
    );
}

fn print_json(robot: &Robot, outcomes: &[BusOutcome], status: u8) -> anyhow::Result<()> {
    let json_findings = |fs: &[Finding]| -> Vec<serde_json::Value> {
        fs.iter()
            .map(|f| {
                let mut v = serde_json::to_value(f).unwrap_or_default();
                v["fixable"] = f.fixable().into();
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
                        "command": fx.command,
                        "ok": fx.result.is_ok(),
                        "error": fx.result.as_ref().err().map(ToString::to_string),
                    })
                })
                .collect();
            serde_json::json!({
                "name": o.name,
                "port": o.target.port,
                "baud": o.target.baud,
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
    println!("{out}");
    Ok(())
}
