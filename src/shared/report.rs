//! The report at the end of a run, as `play`, `follow`, `stream` and
//! `serve` print it.

use servobus_robot::{Finish, Report};

/// Writes the end-of-run report to `out`; `identified`: the lead was
/// found while playing rather than set in the robot file.
pub(crate) fn write_report(
    out: &mut impl std::io::Write,
    r: &Report,
    identified: bool,
) -> std::io::Result<()> {
    write_timing(out, r)?;
    write_links(out, r)?;
    write_lead(out, r, identified)?;
    write_joints(out, r)?;
    if let Some(fault) = &r.fault {
        writeln!(out, "  fault: {fault}")?;
    }
    for w in &r.warnings {
        writeln!(out, "  warning: {w}")?;
    }
    Ok(())
}

/// Writes how the run ended, its rate, its period errors and the buses' counters.
fn write_timing(out: &mut impl std::io::Write, r: &Report) -> std::io::Result<()> {
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
    )
}

/// Writes each bus's link latency, where it came from, and its reply deadline.
fn write_links(out: &mut impl std::io::Write, r: &Report) -> std::io::Result<()> {
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
        for d in &b.eeprom_differences {
            writeln!(
                out,
                "  warning: servo {} ({}) holds {} {}, the robot file's `servo: {}` asks {}: \
                 an EEPROM setting, which a run never writes (`servobus doctor --fix \
                 --write-servos` stores it)",
                d.id, d.joint, d.register, d.held, d.setting, d.wanted
            )?;
        }
    }
    Ok(())
}

/// Writes the lag compensation lead, and whether it was identified while moving.
fn write_lead(out: &mut impl std::io::Write, r: &Report, identified: bool) -> std::io::Result<()> {
    if identified && r.lead_identified && r.lead_ms > 0.0 {
        writeln!(
            out,
            "  lag compensation lead {:.1} ms, identified while moving \
             (`lead_ms: {:.0}` in the robot file applies it from the first cycle)",
            r.lead_ms, r.lead_ms
        )
    } else if identified && r.lead_ms > 0.0 {
        // Too short a run, or too little motion, to identify the lag: no
        // figure worth putting in the robot file.
        writeln!(
            out,
            "  lag compensation lead {:.1} ms (the servos' response lag; too little motion to identify it)",
            r.lead_ms
        )
    } else {
        writeln!(out, "  lag compensation lead {:.1} ms", r.lead_ms)
    }
}

/// Writes the table of each joint's tracking error.
fn write_joints(out: &mut impl std::io::Write, r: &Report) -> std::io::Result<()> {
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
    Ok(())
}
