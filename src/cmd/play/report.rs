//! The plan printed before a run of `servobus play` and the report after it.

use super::*;
use crate::cmd::out::outln;

pub(super) fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    )
}

pub(super) fn print_plan(
    motion: &Motion,
    robot: &Robot,
    trajectory: &Trajectory,
    rate_hz: f64,
    backend: &Backend,
) -> anyhow::Result<()> {
    let on = match backend {
        Backend::Fast => "the simulator, virtual time".to_string(),
        Backend::Simulated => "the simulator, real time".to_string(),
        Backend::Hardware(ports) => format!("servos on {}", ports.join(", ")),
    };
    outln!(
        "{} on {} ({} joints, {} bus{}) via {on}",
        file_name(&motion.path),
        robot.name,
        robot.joint_count(),
        robot.buses.len(),
        if robot.buses.len() == 1 { "" } else { "es" },
    )?;
    if motion.keyframes.is_empty() {
        // A recording has samples, not keyframes (its figures follow the
        // plan).
        outln!(
            "  path {:.2} s through a recording, at {rate_hz} Hz",
            trajectory.duration()
        )?;
    } else {
        outln!(
            "  path {:.2} s, {} keyframes x {}, at {rate_hz} Hz",
            trajectory.duration(),
            motion.keyframes.len(),
            motion.repeat
        )?;
    }
    for bus in &robot.buses {
        let plan = bus.plan(rate_hz)?;
        let every = if plan.read_every() > 1 {
            format!(", each servo read every {} cycles", plan.read_every())
        } else {
            String::new()
        };
        outln!(
            "  bus {}: {} servos at {} baud, {} B and {:.0} us per cycle, {:.1} % of the period \
             (max {:.0} Hz){every}",
            bus.name,
            plan.servos(),
            bus.baud,
            plan.bytes_per_cycle(),
            plan.cycle_time_us(),
            100.0 * plan.utilisation(),
            plan.fastest_rate_hz(),
        )?;
    }
    Ok(())
}

/// Writes the end-of-run report to `out`; `identified`: the lead was
/// found while playing rather than set in the robot file.
pub(crate) fn write_report(
    out: &mut impl std::io::Write,
    r: &Report,
    identified: bool,
) -> std::io::Result<()> {
    writeln!(
        out,
        "{}: {} cycles in {:.2} s, {:.1} Hz achieved of {:.1} Hz requested",
        match r.finish {
            Finish::Completed => "completed",
            Finish::Stopped => "stopped",
            Finish::TorqueOff => "torque off",
            Finish::Fault => "FAULT",
            _ => "ended",
        },
        r.cycles,
        r.duration_s,
        r.achieved_rate_hz,
        r.planned_rate_hz
    )?;
    writeln!(
        out,
        "  period error us: p50 {:.0}  p99 {:.0}  max {:.0};  overruns {}  drift {:.0} us",
        r.period_error_us.p50, r.period_error_us.p99, r.period_error_us.max, r.overruns, r.drift_us
    )?;
    writeln!(
        out,
        "  bus utilisation {:.1} %;  timeouts {}  retries {}  missed replies {}  clamps {}  \
         telemetry dropped {}",
        100.0 * r.utilisation,
        r.timeouts,
        r.retries,
        r.missed_replies,
        r.clamps,
        r.telemetry_dropped
    )?;
    for b in &r.buses {
        let how = if b.latency_learned {
            format!(
                "learned (auto; {} PINGs in {:.1} ms at start-up)",
                b.startup_probes, b.startup_probe_ms
            )
        } else {
            "as the robot file gives it".to_owned()
        };
        writeln!(
            out,
            "  bus {} link: latency mean {:.0} us, p99 {:.0} us, {how}; reply deadline {:.0} us",
            b.name, b.latency_us, b.latency_p99_us, b.reply_deadline_us
        )?;
    }
    if identified && r.lead_identified && r.lead_ms > 0.0 {
        writeln!(
            out,
            "  lag compensation lead {:.1} ms, identified while moving \
             (`lead_ms: {:.0}` in the robot file applies it from the first cycle)",
            r.lead_ms, r.lead_ms
        )?;
    } else if identified && r.lead_ms > 0.0 {
        // Too short a run, or too little motion, to identify the lag: no
        // figure worth putting in the robot file.
        writeln!(
            out,
            "  lag compensation lead {:.1} ms (the servos' response lag; too little motion to identify it)",
            r.lead_ms
        )?;
    } else {
        writeln!(out, "  lag compensation lead {:.1} ms", r.lead_ms)?;
    }
    // The name column fits the longest joint name.
    let w = r.joints.iter().map(|j| j.name.len()).fold(16, usize::max);
    writeln!(
        out,
        "  {:<w$} {:>10} {:>10}   tracking error ({})",
        "joint", "rms", "max", r.units
    )?;
    for j in &r.joints {
        writeln!(
            out,
            "  {:<w$} {:>10.3} {:>10.3}",
            j.name, j.rms_error, j.max_error
        )?;
    }
    if let Some(fault) = &r.fault {
        writeln!(out, "  fault: {fault}")?;
    }
    for w in &r.warnings {
        writeln!(out, "  warning: {w}")?;
    }
    Ok(())
}
