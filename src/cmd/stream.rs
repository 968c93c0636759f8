//! `servobus stream`: joint targets from any program, as JSON lines on
//! standard input, followed smoothly by the robot (the runtime's live
//! targets: a jerk-limited step toward the newest target every cycle).
//!
//! Each line is `{"t": <seconds, optional>, "joints": {"<name>": <angle>}}`,
//! angles in the robot file's units; a line may name some joints only (the
//! others keep their targets). A malformed line is reported on standard
//! error with its number and skipped. End of input stops the robot
//! (jerk limited) and ends the run with its report: on standard error, or
//! with `--json` as the last line of standard output, `{"report": {...}}`.
//! With `--telemetry`, one JSON line per control cycle on standard output:
//! `{"t", "commanded": {..}, "measured": {.. or null}, "faults": [..]}`.

use std::io::{BufRead, Write};
use std::process::ExitCode;
use std::time::Instant;

use servobus_runtime::config::{load_robot, Robot, RobotOptions, Units};
use servobus_runtime::{
    Command, Lead, LiveEvent, Report, RunOptions, Runner, Target, TargetSender, Telemetry,
};

use super::link::{every_port, Ports};

/// Arguments of `servobus stream`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The robot file, or a built-in robot's name, and its port and
    /// calibration.
    #[command(flatten)]
    pub robot: super::RobotArgs,
    /// Write one JSON line per control cycle on stdout: time, commanded and
    /// measured angles per joint, faults.
    #[arg(long)]
    pub telemetry: bool,
    /// Print the report as the last stdout line, `{"report": {...}}`,
    /// instead of as text on stderr.
    #[arg(long)]
    pub json: bool,
    /// Control rate in Hz (default: the robot's).
    #[arg(long)]
    pub rate: Option<f64>,
    /// Seconds without a target after which the joints stop (jerk
    /// limited) and hold until targets come back.
    #[arg(long, default_value_t = 0.25)]
    pub timeout: f64,
}

/// Runs `servobus stream`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    if !(args.timeout.is_finite() && args.timeout > 0.0) {
        return Err(super::exit::input(format!(
            "--timeout {}: give a positive number of seconds",
            args.timeout
        )));
    }
    let robot = load_robot(
        &args.robot.path,
        &RobotOptions::default().calibration(args.robot.hardware.calibration.as_deref()),
    )?;
    let options = RunOptions {
        rate_hz: args.rate,
        lead: robot.lead.map_or_else(Lead::default, Lead::Fixed),
        approach: None,
        target_timeout: std::time::Duration::from_secs_f64(args.timeout),
        ..RunOptions::default()
    };
    let runner = start_live(&robot, args.robot.hardware.port.as_deref(), options)?;
    super::play::install_ctrl_c(&runner);
    let targets = runner.targets();
    let commands = runner.commands();
    let units = robot.units;
    // Standard input on a thread of its own: the telemetry is written
    // meanwhile. End of input stops the run.
    std::thread::Builder::new()
        .name("servobus-stdin".into())
        .spawn(move || {
            read_targets(std::io::stdin().lock(), &targets, units);
            let _ = commands.send(Command::Stop);
        })?;
    let names: Vec<String> = robot.joints().map(|j| j.name.clone()).collect();
    watch(&runner, &names, args.telemetry)?;
    let report = runner.join()?;
    finish(&report, args.json)
}

/// Starts a live run of `robot` through the library's connection: on its
/// ports (`port` for the first bus), through its calibration, or on the
/// built-in simulator in real time.
pub(crate) fn start_live(
    robot: &Robot,
    port: Option<&str>,
    options: RunOptions,
) -> anyhow::Result<Runner> {
    let target = match every_port(robot, port.as_slice()) {
        Ports::None => servobus_robot::Target::Simulator,
        Ports::Every(ports) => servobus_robot::Target::Ports(ports),
        Ports::Missing(bus) => return Err(super::link::no_port(robot, &bus.name, None)),
    };
    let connection = super::link::connect(robot, target)?;
    Ok(connection.live(options)?.into_runner())
}

/// A target line: its `t`, if given, and its joints' angles (rad).
type Parsed = (Option<f64>, Vec<(String, f64)>);

/// The target of a line, or why it is not one.
fn parse_line(line: &str, units: Units) -> Result<Parsed, String> {
    let value: serde_json::Value =
        serde_json::from_str(line).map_err(|e| format!("not JSON: {e}"))?;
    let obj = value
        .as_object()
        .ok_or("not a JSON object: give {\"joints\": {\"<name>\": angle}}")?;
    let t = match obj.get("t") {
        None | Some(serde_json::Value::Null) => None,
        Some(t) => Some(t.as_f64().ok_or("`t` is not a number")?),
    };
    let joints = obj
        .get("joints")
        .and_then(|j| j.as_object())
        .ok_or("no `joints` object: give {\"joints\": {\"<name>\": angle}}")?;
    let mut out = Vec::with_capacity(joints.len());
    for (name, angle) in joints {
        let a = angle
            .as_f64()
            .ok_or_else(|| format!("joint `{name}`: the angle is not a number"))?;
        out.push((name.clone(), units.to_rad(a)));
    }
    Ok((t, out))
}

/// Sends every target line of `input`; reports the malformed and refused
/// ones on stderr with their line numbers. Returns at the end of input (or
/// when the run has ended).
fn read_targets(input: impl BufRead, targets: &TargetSender, units: Units) {
    let started = Instant::now();
    for (i, line) in input.lines().enumerate() {
        let n = i + 1;
        let Ok(line) = line else {
            eprintln!("line {n}: not readable text; input ends here");
            return;
        };
        if line.trim().is_empty() {
            continue;
        }
        let (t, joints) = match parse_line(&line, units) {
            Ok(parsed) => parsed,
            Err(why) => {
                eprintln!("line {n}: {why}; skipped");
                continue;
            }
        };
        let stamp = t.unwrap_or_else(|| started.elapsed().as_secs_f64());
        match targets.send(Target::named(stamp, joints)) {
            Ok(0) => {}
            Ok(k) => eprintln!("line {n}: {k} angle(s) beyond the joint limits, clamped"),
            Err(servobus_runtime::TargetError::Ended) => return,
            Err(why) => eprintln!("line {n}: {why}; skipped"),
        }
    }
}

/// One telemetry line per cycle (all buses' joints) while the run goes on.
fn watch(runner: &Runner, names: &[String], telemetry: bool) -> anyhow::Result<()> {
    let rx = runner.telemetry();
    let n = names.len();
    let mut commanded: Vec<Option<f64>> = vec![None; n];
    let mut measured: Vec<Option<f64>> = vec![None; n];
    let mut faults: Vec<String> = Vec::new();
    let mut cycle: Option<(u64, f64)> = None;
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    let emit = |out: &mut std::io::BufWriter<std::io::StdoutLock>,
                t: f64,
                commanded: &[Option<f64>],
                measured: &[Option<f64>],
                faults: &[String]|
     -> std::io::Result<()> {
        let map = |v: &[Option<f64>]| -> serde_json::Map<String, serde_json::Value> {
            names
                .iter()
                .zip(v)
                .map(|(name, a)| (name.clone(), serde_json::json!(a)))
                .collect()
        };
        let line = serde_json::json!({
            "t": t,
            "commanded": map(commanded),
            "measured": map(measured),
            "faults": faults,
        });
        writeln!(out, "{line}")?;
        out.flush()
    };
    for m in rx.iter() {
        match m {
            Telemetry::Cycle(c) => {
                if let Some((_, t)) = cycle.filter(|(k, _)| *k != c.cycle) {
                    if telemetry {
                        emit(&mut out, t, &commanded, &measured, &faults)?;
                    }
                }
                cycle = Some((c.cycle, c.time_s));
                for j in c.joints() {
                    if let (Some(cm), Some(ms)) =
                        (commanded.get_mut(j.joint), measured.get_mut(j.joint))
                    {
                        *cm = Some(j.commanded);
                        *ms = j.measured;
                    }
                }
            }
            Telemetry::Fault(f) => {
                eprintln!("fault: {f}");
                faults.push(f.to_string());
            }
            Telemetry::Live { event, time_s } => match event {
                LiveEvent::TimedOut => {
                    eprintln!("{time_s:.2} s: no target for the timeout; stopping, then holding")
                }
                LiveEvent::Resumed => eprintln!("{time_s:.2} s: targets again; following"),
                _ => {}
            },
            Telemetry::Rejected(why) => eprintln!("refused: {why}"),
            Telemetry::Finished(_) => break,
            _ => {}
        }
    }
    if let (Some((_, t)), true) = (cycle, telemetry) {
        emit(&mut out, t, &commanded, &measured, &faults)?;
    }
    Ok(())
}

/// The report (stderr, or the last stdout line with `json`) and the exit
/// code: 0 once stopped, 1 after a fault.
fn finish(report: &Report, json: bool) -> anyhow::Result<ExitCode> {
    if json {
        println!("{}", serde_json::json!({ "report": report }));
    } else {
        let mut err = std::io::stderr().lock();
        super::play::write_report(&mut err, report, false)?;
        if let Some(l) = &report.live {
            writeln!(
                err,
                "  targets: {} received, {} refused, {} clamped; {} timeouts, {} resumed",
                l.received, l.refused, l.clamped, l.timeouts, l.resumes
            )?;
        }
    }
    Ok(super::exit::of_finish(report.finish))
}
