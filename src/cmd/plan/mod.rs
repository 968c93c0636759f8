//! `servobus plan`: plan a motion without moving anything, and show its
//! timing, peaks and ranges per joint (or exactly why it cannot be played).

use std::process::ExitCode;

use servobus_config::{load_motion_calibrated, plan_motion, Motion};
use servobus_robot::summary::{PlanSummary, SpaceFigures};

use crate::record::space;
use crate::shared::out::{outln, StdoutError};

mod plot;

/// Arguments of `servobus plan`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The motion: a file, or a built-in name (`servobus list`).
    #[arg(value_parser = crate::shared::flags::motion_arg)]
    pub motion: std::path::PathBuf,
    /// Robot file or built-in name (default: the one the motion file names).
    #[arg(long, value_parser = crate::shared::flags::robot_arg)]
    pub robot: Option<std::path::PathBuf>,
    /// Calibration file of the physical robot: its measured ranges clip the
    /// joint limits the plan is checked against.
    #[arg(long)]
    pub calibration: Option<std::path::PathBuf>,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Draw position and velocity of every joint over time (SVG).
    #[arg(long)]
    pub plot: Option<std::path::PathBuf>,
    /// `--rerun FILE.rrd`, `--rerun-connect [ADDR]`: the planned motion in
    /// 3D in the Rerun viewer, in its own time (nothing moves), with each
    /// joint's margin to its limits and the workspace.
    #[command(flatten)]
    pub rerun: crate::shared::flags::RerunArgs,
}

/// Runs `servobus plan`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    if let Some(path) = &args.plot {
        // The plan's plot is drawn as SVG only.
        crate::shared::flags::check_plot_format(path, &["svg"])?;
    }
    args.rerun.check()?;
    let (motion, robot) = load_motion_calibrated(
        &args.motion,
        args.robot.as_deref(),
        args.calibration.as_deref(),
    )?;
    let traj = plan_motion(&motion, &robot)?;
    let (report, spatial) = PlanSummary::of_motion(&motion, &robot, &traj);
    if let Some(path) = &args.plot {
        let paths = space::paths(spatial.as_ref());
        plot::write(&motion, robot.geometry().as_ref(), &traj, &paths, path)?;
    }
    let mut rerun = args.rerun.start(&robot, motion.units)?;
    rerun.plan(&traj, motion.rate_hz(&robot));
    let recorded = rerun.finish()?;
    if args.json {
        outln!("{}", crate::shared::json::pretty(&report)?)?;
    } else {
        print_text(&report, &motion)?;
        if let Some(path) = &args.plot {
            outln!("plot: {}", path.display())?;
        }
        if let Some(what) = recorded {
            outln!("rerun: {what}")?;
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Prints the plan for people: its header, a row per joint, a row per
/// segment and what the motion does in space.
fn print_text(r: &PlanSummary, motion: &Motion) -> Result<(), StdoutError> {
    let (given, sampled) = keyframe_count(motion);
    outln!(
        "{}: {} keyframes{} ({}{}) on `{}`, {:.3} s at {} Hz ({} cycles)",
        r.motion,
        given,
        if motion.repeat > 1 {
            format!(" x {}", motion.repeat)
        } else {
            String::new()
        },
        sampled,
        r.interpolation,
        r.robot,
        r.duration_s,
        r.rate_hz,
        (r.duration_s * r.rate_hz).ceil()
    )?;
    print_joints(r)?;
    print_segments(r, motion)?;
    if let Some(sp) = &r.spatial {
        print_spatial(sp, &r.units)?;
    }
    Ok(())
}

/// How many keyframes the motion file gives, and how many points those in
/// space (lines, walks, body moves) were sampled into, when they were
/// (`412 points in space, `; empty when none were).
fn keyframe_count(motion: &Motion) -> (usize, String) {
    let mut places: Vec<(usize, usize)> = motion
        .keyframes
        .iter()
        .map(|k| (k.line, k.column))
        .collect();
    places.sort_unstable();
    places.dedup();
    let (given, points) = (places.len(), motion.keyframes.len());
    if given < points {
        (given, format!("{points} points in space, "))
    } else {
        (points, String::new())
    }
}

/// Prints the table of joints: time moving, range and peaks.
fn print_joints(r: &PlanSummary) -> Result<(), StdoutError> {
    let u = &r.units;
    let w = r
        .joints
        .iter()
        .map(|j| j.name.len())
        .max()
        .unwrap_or(5)
        .max(5);
    outln!(
        "\n{:w$}  {:>9}  {:>19}  {:>12}  {:>14}  {:>14}",
        "joint",
        "moving s",
        format!("range {u}"),
        format!("vel {u}/s"),
        format!("acc {u}/s^2"),
        format!("jerk {u}/s^3"),
    )?;
    for j in &r.joints {
        let jerk = j
            .peak_jerk
            .map_or("no limit".to_owned(), |x| format!("{x:.0}"));
        outln!(
            "{:w$}  {:>9.3}  {:>19}  {:>12.1}  {:>14.1}  {:>14}",
            j.name,
            j.moving_s,
            format!("{:.1} .. {:.1}", j.min_position, j.max_position),
            j.peak_velocity,
            j.peak_acceleration,
            jerk,
        )?;
    }
    Ok(())
}

/// The rows of the segment table, each the first and last index of the
/// segments it stands for: the samples of one spatial keyframe (a line, a
/// walk, a body move) share its place in the file, so one row for them all.
fn segment_rows(r: &PlanSummary, motion: &Motion) -> Vec<(usize, usize)> {
    let place = |k: usize| motion.keyframes.get(k).map(|kf| (kf.line, kf.column));
    let mut rows: Vec<(usize, usize)> = Vec::new();
    for (i, seg) in r.segments.iter().enumerate() {
        if let Some(row) = rows.last_mut() {
            let prev = &r.segments[row.1];
            if place(seg.keyframe) == place(prev.keyframe) && seg.repetition == prev.repetition {
                row.1 = i;
                continue;
            }
        }
        rows.push((i, i));
    }
    rows
}

/// The index in the motion file of keyframe `k` (keyframes in space are
/// sampled into many, which share their keyframe's place in the file).
fn file_index(motion: &Motion, k: usize) -> usize {
    let mut seen: Vec<(usize, usize)> = Vec::new();
    for kf in motion.keyframes.iter().take(k + 1) {
        let place = (kf.line, kf.column);
        if !seen.contains(&place) {
            seen.push(place);
        }
    }
    seen.len().saturating_sub(1)
}

/// Prints the table of segments: the keyframe each arrives at, its place
/// in the file and its times.
fn print_segments(r: &PlanSummary, motion: &Motion) -> Result<(), StdoutError> {
    outln!("\nsegments (arriving at keyframe):")?;
    let pw = motion
        .keyframes
        .iter()
        .filter_map(|k| k.pose.as_ref().map(String::len))
        .fold("inline pose".len(), usize::max);
    for (first, last) in segment_rows(r, motion) {
        let count = last - first + 1;
        let s = &r.segments[first];
        let end_s = r.segments[last].end_s;
        let kf = motion.keyframes.get(r.segments[last].keyframe);
        let what = match kf {
            Some(k) if k.pose.is_some() => k.pose.clone().unwrap_or_default(),
            Some(k) if k.tool => "tool pose".to_owned(),
            _ => "inline pose".to_owned(),
        };
        let line = kf.map_or(0, |k| k.line);
        let rep = if motion.repeat > 1 {
            format!(" (repetition {})", s.repetition + 1)
        } else {
            String::new()
        };
        let timed = match kf.and_then(|k| k.at) {
            _ if count > 1 => format!(", {count} samples"),
            // A time the planner chose is the arrival the row shows.
            _ if kf.is_some_and(|k| k.planned_at) => String::new(),
            // A written time, to the ms.
            Some(at) => {
                let ms = format!("{at:.3}");
                format!(", at: {}", ms.trim_end_matches('0').trim_end_matches('.'))
            }
            None => String::new(),
        };
        let what = if count > 1 { "in space" } else { what.as_str() };
        outln!(
            "  {:>3} {:<pw$} line {:<4} {:>8.3} -> {:>8.3} s  ({:.3} s{timed}){rep}",
            file_index(motion, r.segments[last].keyframe),
            what,
            line,
            s.start_s,
            end_s,
            end_s - s.start_s,
        )?;
    }
    Ok(())
}

fn print_spatial(sp: &SpaceFigures, u: &str) -> Result<(), StdoutError> {
    outln!(
        "
in space:"
    )?;
    if let (Some(v), Some(len), Some(d)) = (
        sp.tool_peak_speed_mm_s,
        sp.tool_path_mm,
        sp.min_dexterity_mm_per_rad,
    ) {
        outln!(
            "  tool: peak speed {v:.1} mm/s, path {len:.1} mm; closest to a singular pose: \
             dexterity {d:.1} mm/rad"
        )?;
    }
    if let Some(lift) = sp.max_foot_lift_mm {
        // The margin is over the times a foot is in the air: with none
        // lifted, every foot stands and there is none to give.
        let margin = sp
            .min_stability_margin_mm
            .map_or("every foot stays on the ground".to_owned(), |m| {
                format!("worst stability margin {m:.1} mm")
            });
        outln!("  feet: highest lift {lift:.1} mm; {margin}")?;
        if let (Some(d), Some(t)) = (sp.body_distance_mm, sp.body_turn) {
            outln!("  body: travels {d:.1} mm and turns {t:.1} {u}")?;
        }
        if let Some(low) = sp.low_margin_at_s.as_ref().filter(|l| !l.is_empty()) {
            let at: Vec<String> = low.iter().map(|t| format!("{t:.2}")).collect();
            outln!(
                "  warning: the stability margin drops under 10 mm at {} s",
                at.join(", ")
            )?;
        }
    }
    if let (Some(j), Some(g)) = (&sp.closest_limit_joint, sp.closest_limit) {
        outln!("  closest to a limit: `{j}`, {g:.1} {u} from it")?;
    }
    Ok(())
}
