//! What `servobus follow` leaves once the session has ended: the log, the
//! plot and the recording written, and the report with the follower's
//! latency and error against the leader.

use std::io::Write;
use std::process::ExitCode;

use servobus_config::{Robot, Units};
use servobus_robot::Report;

use super::against::{FollowErrors, ERRORS_FROM};
use super::args::Args;
use super::seen::Seen;
use crate::shared::out::outln;

/// The outputs and the report; exit 0 once stopped, 1 after a fault.
/// `lost`: why the leader's side ended the session, if it did.
pub(super) fn finish(
    args: &Args,
    robot: &Robot,
    report: &Report,
    mut seen: Seen,
    lost: Option<&str>,
) -> anyhow::Result<ExitCode> {
    let names: Vec<String> = robot.joints().map(|j| j.name.clone()).collect();
    if let Some(why) = lost {
        seen.rerun.refused(&anyhow::anyhow!(why.to_owned()));
    }
    let recorded = std::mem::take(&mut seen.rerun).finish();
    write_outputs(args, robot, &names, &mut seen)?;
    let recorded = recorded?;
    let joints = joint_errors(&names, &seen.errors);
    if args.json {
        let follow = follow_json(report, &names, &joints, &seen.stalls, lost);
        let mut value = serde_json::to_value(report)?;
        if let Some(obj) = value.as_object_mut() {
            obj.insert("follow".into(), follow);
        }
        outln!("{}", crate::shared::json::pretty(&value)?)?;
    } else {
        write_text(args, report, &joints, robot.units)?;
        if let Some(what) = recorded {
            outln!("rerun: {what}")?;
        }
    }
    Ok(crate::shared::exit::of_finish(report.finish))
}

/// Writes `--log`, `--plot` and `--record`, each whole or not at all.
fn write_outputs(
    args: &Args,
    robot: &Robot,
    names: &[String],
    seen: &mut Seen,
) -> anyhow::Result<()> {
    let units = robot.units;
    if let Some(log) = seen.log.take() {
        log.finish()?;
    }
    if let (Some(plot), Some(path)) = (&seen.plot, &args.plot) {
        let title = format!("{} following its leader", robot.name);
        plot.draw(path, &title, &units.to_string())?;
    }
    if let Some(path) = &args.record {
        let mut text = format!("time_s,{}\n", names.join(","));
        for (t, row) in &seen.take {
            let cells: Vec<String> = row
                .iter()
                .map(|a| format!("{:.4}", units.to_rad(*a).to_degrees()))
                .collect();
            text += &format!("{t:.4},{}\n", cells.join(","));
        }
        // Whole or not at all, as every output.
        servobus_robot::files::write_atomic(path, text.as_bytes())?;
    }
    Ok(())
}

/// Each joint's error against the leader: `name`, `rms_error`, `max_error`.
fn joint_errors(names: &[String], errors: &FollowErrors) -> Vec<serde_json::Value> {
    names
        .iter()
        .zip(errors.figures())
        .map(|(n, (sq, max, k))| {
            let rms = if *k > 0 { (sq / *k as f64).sqrt() } else { 0.0 };
            serde_json::json!({"name": n, "rms_error": rms, "max_error": max})
        })
        .collect()
}

/// The report's `follow` object: latency, period, errors, stalls, and why
/// the leader was lost.
fn follow_json(
    report: &Report,
    names: &[String],
    joints: &[serde_json::Value],
    stalls: &[(usize, bool, f64, f64)],
    lost: Option<&str>,
) -> serde_json::Value {
    let latency = report.live.as_ref().and_then(|l| l.latency_ms);
    let stalls: Vec<serde_json::Value> = stalls
        .iter()
        .map(|(j, held, t, position)| {
            serde_json::json!({
                "joint": names.get(*j),
                "held": held,
                "time_s": t,
                "position": position,
            })
        })
        .collect();
    serde_json::json!({
        "latency_ms": latency,
        "period_ms": 1e3 / report.planned_rate_hz,
        "errors_from_s": ERRORS_FROM,
        "joints": joints,
        "stalls": stalls,
        "leader_lost": lost,
    })
}

/// Writes the text report to stdout: the run's, then the latency, the
/// error per joint, the stalls and the outputs written.
fn write_text(
    args: &Args,
    report: &Report,
    joints: &[serde_json::Value],
    units: Units,
) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    crate::shared::write_report(&mut out, report, false)?;
    if let Some(q) = report.live.as_ref().and_then(|l| l.latency_ms) {
        writeln!(
            out,
            "  latency leader reading -> follower goal: p50 {:.1} ms  p99 {:.1} ms  max {:.1} ms",
            q.p50, q.p99, q.max
        )?;
    }
    writeln!(out, "  follower vs leader after {ERRORS_FROM} s ({units}):")?;
    for j in joints {
        writeln!(
            out,
            "    {:<16} rms {:>8.3}  max {:>8.3}",
            j["name"].as_str().unwrap_or("?"),
            j["rms_error"].as_f64().unwrap_or(0.0),
            j["max_error"].as_f64().unwrap_or(0.0)
        )?;
    }
    for j in report.stalled_joints() {
        writeln!(
            out,
            "  {} stalled {} time(s), held with bounded effort for {:.1} s",
            j.name, j.stalls, j.stalled_s
        )?;
    }
    for (flag, path) in [
        ("log", &args.log),
        ("plot", &args.plot),
        ("recording", &args.record),
    ] {
        if let Some(path) = path {
            writeln!(out, "{flag}: {}", path.display())?;
        }
    }
    Ok(())
}
