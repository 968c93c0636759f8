//! The inputs of `servobus play`: the motion or recording, checked and
//! planned, and the outputs checked before anything moves.

use std::path::Path;

use servobus_config::{
    check_motion_length, limits, load_motion_calibrated, plan_motion, Motion, Robot, Units,
};
use servobus_robot::Trajectory;

use super::args::Args;
use crate::record::read_recording;

/// Plot formats `--plot` writes, by file extension.
pub(super) const PLOT_FORMATS: [&str; 2] = ["svg", "png"];

/// Fails at once on an output that could not be written after the run: a
/// plot format not supported, or a directory that does not exist.
pub(super) fn check_outputs(args: &Args) -> anyhow::Result<()> {
    if let Some(path) = &args.plot {
        crate::shared::flags::check_plot_format(path, &PLOT_FORMATS)?;
    }
    for (flag, path) in [("--plot", &args.plot), ("--log", &args.log)] {
        if let Some(path) = path {
            crate::shared::flags::check_writable(flag, path)?;
        }
    }
    Ok(())
}

/// Departures from a recording smaller than this are not reported, deg:
/// half a position tick of a 4096-tick servo (0.088 deg), below what the
/// servos can show, and far above what the rounding of a log's numbers
/// makes the filter leave the recording by (about 1e-6 deg).
const REPORTED_DEPARTURE_DEG: f64 = 0.044;

/// The most departures the text report names; the JSON report has them
/// all.
const NAMED_DEPARTURES: usize = 3;

/// A recording played back: how closely, and where and why it departs.
pub(super) struct RecordingInfo {
    samples: usize,
    span_s: f64,
    names: Vec<String>,
    max_rad: Vec<f64>,
    rms_rad: Vec<f64>,
    missing: Vec<String>,
    /// The log's column read, if a log.
    column: Option<String>,
    /// How long the path moves before the recording's first sample, s.
    lead_s: f64,
    /// Departures above [`REPORTED_DEPARTURE_DEG`], largest first.
    departures: Vec<servobus_robot::path::Departure>,
    /// Per robot joint, the recording's `(time, position)` samples on the
    /// path's clock (its own times shifted by `lead_s`), in the motion's
    /// units; empty for a joint not recorded. Drawn on `--plot`.
    pub(super) series: Vec<Vec<(f64, f64)>>,
}

impl RecordingInfo {
    /// The worst joint's departure, and where and why the path leaves the
    /// recording, in one line.
    pub(super) fn describe(&self, u: Units) -> String {
        let worst = (0..self.max_rad.len())
            .max_by(|&a, &b| self.max_rad[a].total_cmp(&self.max_rad[b]))
            .unwrap_or(0);
        let what = self
            .column
            .as_deref()
            .map_or_else(String::new, |c| format!(" of {c}"));
        let mut text = format!(
            "recording: {} samples{what} over {:.2} s, played through them within the limits; \
             departs from it by at most {:.2} {u} ({}), rms {:.2} {u}",
            self.samples,
            self.span_s,
            u.from_rad(self.max_rad.get(worst).copied().unwrap_or(0.0)),
            self.names.get(worst).map_or("?", String::as_str),
            u.from_rad(self.rms_rad.get(worst).copied().unwrap_or(0.0)),
        );
        if self.departures.is_empty() {
            text += ", nowhere by more than a position tick";
        } else {
            let named: Vec<String> = self
                .departures
                .iter()
                .take(NAMED_DEPARTURES)
                .map(|d| self.departure(d, u))
                .collect();
            text += &format!("; where it breaks a limit: {}", named.join("; "));
            let more = self.departures.len().saturating_sub(NAMED_DEPARTURES);
            if more > 0 {
                text += &format!("; and {more} more (--json lists them)");
            }
        }
        if self.lead_s > 0.0 {
            text += &format!(
                "; the path starts {:.3} s before its first sample",
                self.lead_s
            );
        }
        if !self.missing.is_empty() {
            text += &format!("; not recorded, held at rest: {}", self.missing.join(", "));
        }
        text
    }

    /// One departure in words: joint, when, which limit, how far.
    fn departure(&self, d: &servobus_robot::path::Departure, u: Units) -> String {
        let (peak, limit, unit) = magnitudes(d, u);
        format!(
            "{} {:.2}-{:.2} s, {} {peak:.1} beyond its limit {limit:.1} {unit} (off by up to {:.2} {u} at {:.2} s)",
            self.names.get(d.joint).map_or("?", String::as_str),
            d.start,
            d.end,
            d.quantity,
            u.from_rad(d.max_departure),
            d.at,
        )
    }

    pub(super) fn json(&self, u: Units) -> serde_json::Value {
        let joints: Vec<serde_json::Value> = self
            .names
            .iter()
            .enumerate()
            .map(|(j, name)| {
                serde_json::json!({
                    "name": name,
                    "max_departure": u.from_rad(self.max_rad[j]),
                    "rms_departure": u.from_rad(self.rms_rad[j]),
                })
            })
            .collect();
        let departures: Vec<serde_json::Value> = self
            .departures
            .iter()
            .map(|d| {
                let (peak, limit, unit) = magnitudes(d, u);
                serde_json::json!({
                    "joint": self.names.get(d.joint).map_or("?", String::as_str),
                    "start_s": d.start,
                    "end_s": d.end,
                    "limit": d.quantity.to_string(),
                    "peak": peak,
                    "max": limit,
                    "unit": unit,
                    "max_departure": u.from_rad(d.max_departure),
                    "at_s": d.at,
                })
            })
            .collect();
        serde_json::json!({
            "samples": self.samples,
            "span_s": self.span_s,
            "column": self.column,
            "lead_s": self.lead_s,
            "joints": joints,
            "departures": departures,
        })
    }
}

/// A departure's peak and limit in the robot's units, and their unit.
fn magnitudes(d: &servobus_robot::path::Departure, u: Units) -> (f64, f64, String) {
    let unit = match d.quantity {
        servobus_robot::path::Quantity::Position => u.to_string(),
        servobus_robot::path::Quantity::Velocity => format!("{u}/s"),
        servobus_robot::path::Quantity::Acceleration => format!("{u}/s^2"),
        _ => format!("{u}/s^3"),
    };
    (u.from_rad(d.peak), u.from_rad(d.limit), unit)
}

pub(super) type Loaded = (Motion, Robot, Trajectory, Option<RecordingInfo>, f64);

/// The motion file planned, or the recording (`.csv`) filtered, with the
/// control rate; every limit and the buses' budgets checked.
pub(super) fn load(args: &Args) -> anyhow::Result<Loaded> {
    let recorded = args
        .motion
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let (motion, mut robot) = if recorded {
        let robot = recording_robot(args)?;
        (recording_motion(&args.motion, &robot), robot)
    } else {
        load_motion_calibrated(
            &args.motion,
            args.robot.as_deref(),
            args.hardware.calibration.as_deref(),
        )?
    };
    // `--rate` is checked by its parser, the files' rates by the loaders.
    let rate_hz = args.rate.unwrap_or_else(|| motion.rate_hz(&robot));
    check_buses(args, &mut robot, rate_hz)?;
    if !recorded {
        let trajectory = plan_motion(&motion, &robot)?;
        check_motion_length(&motion, &trajectory, rate_hz)?;
        return Ok((motion, robot, trajectory, None, rate_hz));
    }
    let (trajectory, info) = load_recording(args, &motion, &robot, rate_hz)?;
    Ok((motion, robot, trajectory, Some(info), rate_hz))
}

/// The robot a recorded path plays on: `--robot`, which it needs.
fn recording_robot(args: &Args) -> anyhow::Result<Robot> {
    let Some(robot_path) = &args.robot else {
        return Err(crate::shared::exit::input(format!(
            "{}: a recorded path names no robot; give --robot FILE",
            args.motion.display()
        )));
    };
    Ok(servobus_config::load_robot(
        robot_path,
        &servobus_config::RobotOptions::default()
            .calibration(args.hardware.calibration.as_deref())
            .to_play(),
    )?)
}

/// Applies `--round-robin` and `--busy-poll` to every bus and checks that
/// `rate_hz` fits each one's budget.
fn check_buses(args: &Args, robot: &mut Robot, rate_hz: f64) -> anyhow::Result<()> {
    for bus in &mut robot.buses {
        bus.round_robin |= args.round_robin;
        bus.busy_poll |= args.busy_poll;
        if let Err(why) = bus.check_rate(rate_hz) {
            let why = crate::shared::flags::rate_advice(&why);
            return Err(crate::shared::exit::input(format!(
                "bus `{}`: {why}",
                bus.name
            )));
        }
    }
    Ok(())
}

/// The recording `args.motion` read and played through the robot's limits
/// at `rate_hz`: the path, and how closely it follows the recording.
fn load_recording(
    args: &Args,
    motion: &Motion,
    robot: &Robot,
    rate_hz: f64,
) -> anyhow::Result<(Trajectory, RecordingInfo)> {
    // A recording that cannot be read is a bad input file (exit 2).
    let rec = read_recording(&args.motion, robot).map_err(crate::shared::exit::invalid)?;
    let span_s = rec.times[rec.times.len() - 1] - rec.times[0];
    if let Err(e) = limits::check_recording(span_s, rate_hz, robot.joint_count()) {
        return Err(crate::shared::exit::input(format!(
            "{}: the recording is too long to play: {e}",
            args.motion.display()
        )));
    }
    let limits = servobus_config::joint_limits(robot);
    let options = servobus_robot::path::TrackOptions {
        step: 1.0 / rate_hz,
        resolution: rec.resolution,
    };
    let tracked = servobus_robot::path::track_with(&limits, &rec.times, &rec.samples, &options)
        .map_err(|e| {
            anyhow::anyhow!("{}: cannot play this recording: {e}", args.motion.display())
        })?;
    let lead_s = tracked.recording_start;
    let names = names_of(robot);
    let series = names
        .iter()
        .enumerate()
        .map(|(j, name)| {
            if rec.missing.contains(name) {
                return Vec::new();
            }
            rec.times
                .iter()
                .zip(&rec.samples)
                .map(|(t, q)| (t - rec.times[0] + lead_s, motion.units.from_rad(q[j])))
                .collect()
        })
        .collect();
    let info = RecordingInfo {
        samples: rec.times.len(),
        span_s,
        names,
        max_rad: tracked.max_deviation,
        rms_rad: tracked.rms_deviation,
        missing: rec.missing,
        column: rec.column,
        lead_s,
        departures: reported(tracked.departures),
        series,
    };
    Ok((tracked.trajectory, info))
}

/// The departures worth reporting (above [`REPORTED_DEPARTURE_DEG`]),
/// largest first.
fn reported(
    departures: Vec<servobus_robot::path::Departure>,
) -> Vec<servobus_robot::path::Departure> {
    let reported = Units::Deg.to_rad(REPORTED_DEPARTURE_DEG);
    let mut departures: Vec<_> = departures
        .into_iter()
        .filter(|d| d.max_departure > reported)
        .collect();
    departures.sort_by(|a, b| b.max_departure.total_cmp(&a.max_departure));
    departures
}

/// A stand-in motion for a recording (its name, the robot's joints), so the
/// plan and report read the same as for a motion file.
pub(super) fn recording_motion(path: &Path, robot: &Robot) -> Motion {
    Motion {
        path: path.to_owned(),
        robot_path: robot.path.clone(),
        units: Units::Deg,
        rate_hz: None,
        joints: names_of(robot),
        keyframes: Vec::new(),
        repeat: 1,
        on_limit: Default::default(),
        interpolation: Default::default(),
    }
}

/// The robot's joint names, in its joint order.
pub(super) fn names_of(robot: &Robot) -> Vec<String> {
    robot.joints().map(|j| j.name.clone()).collect()
}
