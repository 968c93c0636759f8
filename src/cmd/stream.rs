//! `servobus stream`: joint targets from any program, as JSON lines on
//! standard input, followed smoothly by the robot (the runtime's live
//! targets: a jerk-limited step toward the newest target every cycle).
//!
//! Each line is a target, `{"t": <seconds, optional>, "joints": {"<name>":
//! <angle>}}`, or an action chunk, `{"chunk": {"t0": <seconds, optional>,
//! "dt": <seconds>, "joints": {"<name>": [<angle>, ...]}}}`, angles in the
//! robot file's units ([`servobus_robot::stream`]); a line may name some
//! joints only (the others keep their targets). A robot with a mobile base
//! also takes `{"base": {"x": m/s, "y": m/s, "theta": <units>/s}}`: its
//! wheels' speeds, scaled together within their limits. A line's
//! `{"grasp": {"<joint>": <effort %>}}` tells a gripper to close until it
//! meets something and hold there with that share of its servo's torque
//! (see [`servobus_robot::grasp`]); a later position releases it. A malformed line, one
//! longer than 1 MiB or one that is not UTF-8 is reported on standard
//! error with its number, skipped and counted. End of input stops the
//! robot (jerk limited) and ends the run with its report: on standard
//! error, or with `--json` as the last line of standard output,
//! `{"report": {...}, "skipped_lines": <count>}`.
//! With `--telemetry`, one JSON line per control cycle on standard output:
//! `{"t", "commanded": {..}, "measured": {.. or null}, "faults": [..]}`,
//! and for a robot with a base its odometry, `base_x_m`, `base_y_m`,
//! `base_theta_deg`.

use std::io::{BufRead, Write};
use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use servobus_config::{load_robot, Robot, RobotOptions};
use servobus_robot::{
    live_options, Command, LiveEvent, Report, Run, RunOptions, TargetSender, Telemetry,
};

use servobus_robot::grasp::{GraspCause, GraspEvent};
use servobus_robot::odometry::{pose_figures, Odometer, Odometry};
use servobus_robot::stream::{parse_line_for, MAX_LINE_BYTES};

use crate::shared::flags::Recording;
use crate::shared::out::{errln, outln};
use crate::shared::ports::start_live;

/// Arguments of `servobus stream`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The robot file, or a built-in robot's name, and its port and
    /// calibration.
    #[command(flatten)]
    pub robot: crate::shared::flags::RobotArgs,
    /// `--write-servos`: store what the robot file asks of the servos'
    /// EEPROM before the run.
    #[command(flatten)]
    pub store: crate::shared::flags::WriteServosArg,
    /// Write one JSON line per control cycle on stdout: time, commanded and
    /// measured angles per joint, faults.
    #[arg(long)]
    pub telemetry: bool,
    /// Print the report as the last stdout line, `{"report": {...}}`,
    /// instead of as text on stderr.
    #[arg(long)]
    pub json: bool,
    /// Control rate in Hz (default: the robot's).
    #[arg(long, value_parser = crate::shared::args::rate_arg)]
    pub rate: Option<f64>,
    /// `--rerun FILE.rrd`, `--rerun-connect [ADDR]`: the robot following
    /// the targets, in the Rerun viewer.
    #[command(flatten)]
    pub rerun: crate::shared::flags::RerunArgs,
    /// Seconds without a target after which the joints stop (jerk
    /// limited) and hold until targets come back.
    #[arg(long, default_value = "0.25", value_parser = crate::shared::args::timeout_arg)]
    pub timeout: std::time::Duration,
}

/// Runs `servobus stream`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let robot = load_robot(
        &args.robot.path,
        &RobotOptions::default().calibration(args.robot.hardware.calibration.as_deref()),
    )?;
    let rerun = args.rerun.start(&robot, robot.units)?;
    let options = RunOptions {
        rate_hz: args.rate,
        target_timeout: args.timeout,
        ..live_options(&robot)
    };
    let started = start_live(
        &robot,
        args.robot.hardware.port.as_deref(),
        options,
        args.store.write_servos,
    );
    let (runner, mut rerun) = rerun.unless_refused(started)?;
    crate::shared::install_ctrl_c(runner.commands());
    let targets = runner.targets();
    let commands = runner.commands();
    let lines_robot = robot.clone();
    // Standard input on a thread of its own: the telemetry is written
    // meanwhile. End of input stops the run.
    let skipped = std::sync::Arc::new(AtomicU64::new(0));
    let skips = std::sync::Arc::clone(&skipped);
    std::thread::Builder::new()
        .name("servobus-stdin".into())
        .spawn(move || {
            read_targets(std::io::stdin().lock(), &targets, &lines_robot, &skips);
            let _ = commands.send(Command::Stop);
        })?;
    let names: Vec<String> = robot.joints().map(|j| j.name.clone()).collect();
    let odometer = servobus_robot::odometry::Odometer::of(&robot, robot.units);
    let lost = watch(&runner, &names, (odometer, &mut rerun), args.telemetry)?;
    let (report, rerun) = rerun.unless_refused(runner.join().map_err(Into::into))?;
    if let Some(what) = rerun.finish()? {
        errln!("rerun: {what}");
    }
    let skipped = skipped.load(Ordering::Relaxed);
    let code = finish(&report, skipped, args.json && !lost)?;
    if lost {
        return Ok(ExitCode::from(crate::shared::exit::PROBLEM));
    }
    Ok(code)
}

/// Reads lines of at most [`MAX_LINE_BYTES`] from `input`: each line (without
/// its end), `Err(true)` for a line too long (skipped whole), `Err(false)`
/// at the end of input or on a read error.
fn next_line(input: &mut impl BufRead, buf: &mut Vec<u8>) -> Result<(), bool> {
    buf.clear();
    let mut long = false;
    loop {
        let chunk = match input.fill_buf() {
            Ok(c) => c,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(_) => return Err(false),
        };
        if chunk.is_empty() {
            return if long {
                Err(true)
            } else if buf.is_empty() {
                Err(false)
            } else {
                Ok(())
            };
        }
        let (part, end) = match chunk.iter().position(|&b| b == b'\n') {
            Some(i) => (&chunk[..i], Some(i + 1)),
            None => (chunk, None),
        };
        if !long && buf.len() + part.len() <= MAX_LINE_BYTES {
            buf.extend_from_slice(part);
        } else {
            long = true;
            buf.clear();
        }
        let used = end.unwrap_or(chunk.len());
        input.consume(used);
        if end.is_some() {
            return if long { Err(true) } else { Ok(()) };
        }
    }
}

/// Sends every target and chunk line of `input`; reports the malformed
/// and refused ones on stderr with their line numbers, and counts them in
/// `skipped`. Returns at the end of input (or when the run has ended).
fn read_targets(
    mut input: impl BufRead,
    targets: &TargetSender,
    robot: &Robot,
    skipped: &AtomicU64,
) {
    let skip = || skipped.fetch_add(1, Ordering::Relaxed);
    let started = Instant::now();
    let mut buf = Vec::new();
    for n in 1usize.. {
        match next_line(&mut input, &mut buf) {
            Ok(()) => {}
            Err(true) => {
                errln!(
                    "line {n}: longer than {} MiB; skipped",
                    MAX_LINE_BYTES >> 20
                );
                skip();
                continue;
            }
            Err(false) => return,
        }
        let Ok(line) = std::str::from_utf8(&buf) else {
            errln!("line {n}: not UTF-8 text; skipped");
            skip();
            continue;
        };
        if line.trim().is_empty() {
            continue;
        }
        let arrival = started.elapsed().as_secs_f64();
        let input = match parse_line_for(line, robot, arrival) {
            Ok(parsed) => parsed,
            Err(why) => {
                errln!("line {n}: {why}; skipped");
                skip();
                continue;
            }
        };
        match input.send(targets) {
            Ok(0) => {}
            Ok(k) => errln!("line {n}: {k} angle(s) beyond the joint limits, clamped"),
            Err(servobus_robot::TargetError::Ended) => return,
            Err(why) => {
                errln!("line {n}: {why}; skipped");
                skip();
            }
        }
    }
}

/// The telemetry line of the cycle at `t` s: every joint's commanded and
/// measured angle (`joints`), the faults so far, and a mobile base's
/// odometry when given.
fn telemetry_line(
    names: &[String],
    t: f64,
    joints: (&[Option<f64>], &[Option<f64>]),
    faults: &[String],
    pose: Option<Odometry>,
) -> serde_json::Value {
    let map = |v: &[Option<f64>]| -> serde_json::Map<String, serde_json::Value> {
        names
            .iter()
            .zip(v)
            .map(|(name, a)| (name.clone(), serde_json::json!(a)))
            .collect()
    };
    let mut line = serde_json::json!({
        "t": t,
        "commanded": map(joints.0),
        "measured": map(joints.1),
        "faults": faults,
    });
    if let (Some(pose), Some(fields)) = (pose, line.as_object_mut()) {
        for (key, value) in pose_figures(&pose) {
            fields.insert(key.to_owned(), serde_json::json!(value));
        }
    }
    line
}

/// What lowered a grasp or made it let go, as stderr says it: `warm (62
/// C)` (`hot` the word for temperature), or `drawing 1450 mA`.
fn grasp_cause(
    cause: GraspCause,
    temperature_c: f64,
    current_ma: Option<f64>,
    hot: &str,
) -> String {
    match (cause, current_ma) {
        (GraspCause::Current, Some(ma)) => format!("drawing {ma:.0} mA"),
        _ => format!("{hot} ({temperature_c:.0} C)"),
    }
}

/// Says on stderr what a telemetry message other than a cycle, a fault or
/// the end tells: the live following stopped or resumed, a grasp's news, a
/// command refused (`names`: the joints').
fn say(m: &Telemetry, names: &[String]) {
    match m {
        Telemetry::Grasp(g) => {
            let joint = names.get(g.joint).map_or("?", String::as_str);
            let what = match g.event {
                GraspEvent::Closing { effort_pct } => {
                    format!("closing to grasp with {effort_pct:.0} % of its torque")
                }
                GraspEvent::Lowered {
                    effort_pct,
                    temperature_c,
                    current_ma,
                    cause,
                } => format!(
                    "{}: its grasp eased to {effort_pct:.0} %",
                    grasp_cause(cause, temperature_c, current_ma, "warm")
                ),
                GraspEvent::LetGo {
                    temperature_c,
                    current_ma,
                    cause,
                } => format!(
                    "{}: it let go of what it held",
                    grasp_cause(cause, temperature_c, current_ma, "hot")
                ),
                GraspEvent::Released => "released".to_owned(),
                _ => return,
            };
            errln!("{:.2} s: {joint}: {what}", g.time_s);
        }
        Telemetry::Live { event, time_s } => match event {
            LiveEvent::TimedOut => {
                errln!("{time_s:.2} s: no target for the timeout; stopping, then holding")
            }
            LiveEvent::Resumed => errln!("{time_s:.2} s: targets again; following"),
            _ => {}
        },
        Telemetry::Rejected(why) => errln!("refused: {why}"),
        _ => {}
    }
}

/// One telemetry line per cycle (all buses' joints, and a mobile base's
/// odometry when `odometer` is given) while the run goes on, every message
/// handed to the recording for the Rerun viewer too. Returns
/// whether the telemetry could not all be written (the run was then
/// stopped).
fn watch(
    runner: &Run,
    names: &[String],
    (mut odometer, rerun): (Option<Odometer>, &mut Recording),
    mut telemetry: bool,
) -> anyhow::Result<bool> {
    let mut lost = false;
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
                faults: &[String],
                pose: Option<Odometry>|
     -> std::io::Result<()> {
        let line = telemetry_line(names, t, (commanded, measured), faults, pose);
        let text = crate::shared::json::line(&line).map_err(std::io::Error::other)?;
        writeln!(out, "{text}")?;
        out.flush()
    };
    for m in rx.iter().inspect(|m| rerun.telemetry(m)) {
        match m {
            Telemetry::Cycle(c) => {
                if let Some((_, t)) = cycle.filter(|(k, _)| *k != c.cycle) {
                    let pose = odometer.as_ref().map(Odometer::pose);
                    if telemetry && emit(&mut out, t, &commanded, &measured, &faults, pose).is_err()
                    {
                        // Nobody reads the telemetry any more (a closed
                        // pipe) or it cannot be written: stop as on
                        // Ctrl-C, the report still goes to stderr.
                        telemetry = false;
                        lost = true;
                        errln!("the telemetry cannot be written to stdout; stopping");
                        let _ = runner.commands().try_send(Command::Stop);
                    }
                }
                cycle = Some((c.cycle, c.time_s));
                if let Some(o) = odometer.as_mut() {
                    o.take(&c);
                }
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
                errln!("fault: {f}");
                faults.push(f.to_string());
            }
            Telemetry::Finished(_) => break,
            other => say(&other, names),
        }
    }
    if let (Some((_, t)), true) = (cycle, telemetry) {
        lost |= emit(
            &mut out,
            t,
            &commanded,
            &measured,
            &faults,
            odometer.as_ref().map(Odometer::pose),
        )
        .is_err();
    }
    Ok(lost)
}

/// The report (stderr, or the last stdout line with `json`, with the
/// count of input lines skipped) and the exit code: 0 once stopped, 1
/// after a fault.
fn finish(report: &Report, skipped: u64, json: bool) -> anyhow::Result<ExitCode> {
    if json {
        let value = serde_json::json!({ "report": report, "skipped_lines": skipped });
        outln!("{}", crate::shared::json::line(&value)?)?;
    } else {
        let mut err = std::io::stderr().lock();
        crate::shared::write_report(&mut err, report, false)?;
        if let Some(l) = &report.live {
            writeln!(
                err,
                "  targets: {} received, {} refused, {} clamped; {} timeouts, {} resumed; \
                 {skipped} input line(s) skipped",
                l.received, l.refused, l.clamped, l.timeouts, l.resumes
            )?;
            for j in l.envelope.iter().filter(|j| j.overshoot > 0.05) {
                writeln!(
                    err,
                    "  {}: {:.1} {u} beyond its targets' range, its stopping distance {:.1} {u}",
                    j.name,
                    j.overshoot,
                    j.allowance,
                    u = report.units
                )?;
            }
        }
    }
    Ok(crate::shared::exit::of_finish(report.finish))
}
