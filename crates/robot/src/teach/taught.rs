//! From what a take captured to the motion file: limits checked (never
//! clamped), idle ends trimmed, identical keyframes merged, the pace kept,
//! a recorded path reduced to few keyframes that play as recorded.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use servobus_trajectory::{self as traj, JointState, PlanOptions, TimedShape};

use super::{distance, TeachError};
use crate::config::limits::Fixed;
use crate::config::{joint_limits, limit_origins, plan_input, Keyframe, Motion, Robot};

/// A timed keyframe: seconds from the start, and every joint's angle in
/// the robot file's units.
pub type TimedPose = (f64, Vec<f64>);

/// Two keyframes closer than this (robot units, per joint) are the same
/// pose: the motion file writes angles to 0.01.
const SAME_POSE: f64 = 0.005;

/// How long a take interrupted while the robot moved may take to come to
/// rest at its last pose, s: doubled from the first figure until the path
/// plays within the limits.
const SETTLE_TRIES_S: [f64; 5] = [0.25, 0.5, 1.0, 2.0, 4.0];

/// Refuses a pose with a joint outside its limits: a taught angle is never
/// clamped (a clamped pose is a pose nobody taught).
///
/// # Errors
/// [`TeachError::OutsideLimits`] for the first joint outside, with its value,
/// its limits and where the limit passed comes from.
pub fn check_pose(robot: &Robot, pose: &[f64]) -> Result<(), TeachError> {
    for (j, &value) in robot.joints().zip(pose) {
        if value < j.min || value > j.max || !value.is_finite() {
            let [lo, hi] = limit_origins(j, robot.units);
            return Err(TeachError::OutsideLimits {
                joint: j.name.clone(),
                value,
                min: j.min,
                max: j.max,
                units: robot.units,
                origin: if value < j.min { lo } else { hi },
            });
        }
    }
    Ok(())
}

/// How much of the idle time next to the motion a trimmed take keeps, s: a
/// hand eases in and out below the still threshold, and the path must
/// start and end at rest.
pub const IDLE_KEPT_S: f64 = 0.5;

/// `samples` without the idle time at either end: the robot is idle until
/// it first moves more than `still` (robot units) from where it started,
/// and again once it stays within `still` of where it ended. Up to
/// [`IDLE_KEPT_S`] of each idle end is kept, for the ease in and out. A
/// take in which nothing moved keeps its first sample.
pub fn trim_idle(samples: &[TimedPose], still: f64) -> &[TimedPose] {
    let (Some(first), Some(last)) = (samples.first(), samples.last()) else {
        return samples;
    };
    let Some(moves) = samples
        .iter()
        .position(|s| distance(&s.1, &first.1) > still)
    else {
        return &samples[..1];
    };
    let rests = samples
        .iter()
        .rposition(|s| distance(&s.1, &last.1) > still)
        .map_or(samples.len() - 1, |i| i + 1)
        .max(moves);
    let from = samples[..moves]
        .iter()
        .position(|s| s.0 >= samples[moves].0 - IDLE_KEPT_S)
        .unwrap_or(0);
    let to = rests
        + samples[rests..]
            .iter()
            .rposition(|s| s.0 <= samples[rests].0 + IDLE_KEPT_S)
            .unwrap_or(0);
    &samples[from..=to]
}

/// `keyframes` with each run of identical consecutive poses merged: a timed
/// run keeps its first and last keyframe (the robot holds still between
/// them), an untimed run keeps one.
pub fn merge_identical(keyframes: Vec<TimedPose>, timed: bool) -> Vec<TimedPose> {
    let same = |a: &TimedPose, b: &TimedPose| distance(&a.1, &b.1) <= SAME_POSE;
    let mut out: Vec<TimedPose> = Vec::with_capacity(keyframes.len());
    for k in keyframes {
        let n = out.len();
        match (out.last(), n.checked_sub(2).and_then(|i| out.get(i))) {
            (Some(last), _) if same(last, &k) && !timed => {}
            // A third of a run: the run's last keyframe moves to it.
            (Some(last), Some(before)) if same(last, &k) && same(before, &k) => out[n - 1] = k,
            _ => out.push(k),
        }
    }
    out
}

/// A recorded path reduced to keyframes.
#[derive(Debug, Clone, PartialEq)]
pub struct Reduced {
    /// The timed keyframes, times from the first.
    pub keyframes: Vec<TimedPose>,
    /// When the recording ended while the robot moved: the time added after
    /// the last sample for the path to come to rest at its last pose, s.
    pub settle_s: Option<f64>,
}

/// The planner options of a reduced path, as its motion file sets them
/// (`interpolation: cubic`, `on_limit: error`): the smooth spline through
/// the keyframes, refused where it breaks a limit. The reduction checks the
/// very plan `play` makes of the file, so the file plays as checked.
fn reduced_options() -> PlanOptions {
    PlanOptions {
        shape: TimedShape::Cubic,
        on_limit: traj::OnLimit::Error,
        ..PlanOptions::default()
    }
}

/// The sample halfway through the longest gap between chosen keyframes.
fn split_longest(chosen: &[usize]) -> Option<(usize, usize)> {
    let (at, gap) = chosen
        .windows(2)
        .enumerate()
        .map(|(k, w)| (k + 1, w[1] - w[0]))
        .max_by_key(|&(_, g)| g)?;
    (gap >= 2).then(|| (at, chosen[at - 1] + gap / 2))
}

/// The fewest timed keyframes (chosen among `samples`) whose planned path
/// stays within `tolerance` (robot units) of every sample and within every
/// limit. Times count from the first sample. Keyframes are added one at a
/// time at the worst-reproduced sample until the path fits (or every
/// sample is a keyframe); where the spline breaks a limit (it swings past
/// a joint limit between keyframes far apart), the longest gap is split
/// first. A recording that ends while the robot moves (a take stopped with
/// Ctrl-C) cannot stop at its last sample within the limits: its last pose
/// is then held a moment later ([`Reduced::settle_s`]), the shortest of
/// 0.25, 0.5, 1, 2 and 4 s that plays.
///
/// # Errors
/// [`TeachError::OutsideLimits`] for a sample outside the limits;
/// [`TeachError::Unplayable`] when no keyframes play within the limits.
pub fn reduce(robot: &Robot, samples: &[TimedPose], tolerance: f64) -> Result<Reduced, TeachError> {
    let Some(last) = samples.last() else {
        return Ok(Reduced {
            keyframes: Vec::new(),
            settle_s: None,
        });
    };
    for (_, pose) in samples {
        check_pose(robot, pose)?;
    }
    let mut reason = match reduce_within(robot, samples, tolerance) {
        Ok(keyframes) => {
            return Ok(Reduced {
                keyframes,
                settle_s: None,
            })
        }
        Err(e) => e,
    };
    let mut extended = samples.to_vec();
    extended.push(last.clone());
    for settle in SETTLE_TRIES_S {
        if let Some(end) = extended.last_mut() {
            end.0 = last.0 + settle;
        }
        match reduce_within(robot, &extended, tolerance) {
            Ok(keyframes) => {
                return Ok(Reduced {
                    keyframes,
                    settle_s: Some(settle),
                })
            }
            Err(e) => reason = e,
        }
    }
    Err(TeachError::Unplayable { reason })
}

/// [`reduce`] of samples as they are: the keyframes, or the planner's
/// refusal once every split has been tried.
fn reduce_within(
    robot: &Robot,
    samples: &[TimedPose],
    tolerance: f64,
) -> Result<Vec<TimedPose>, String> {
    let t0 = samples.first().map_or(0.0, |s| s.0);
    let limits = joint_limits(robot);
    let units = robot.units;
    let mut chosen = vec![0, samples.len().saturating_sub(1)];
    chosen.dedup();
    let mut state = vec![JointState::default(); robot.joint_count()];
    loop {
        let keyframes: Vec<traj::Keyframe> = chosen
            .iter()
            .map(|&i| {
                let (t, p) = &samples[i];
                let k = traj::Keyframe::new(p.iter().map(|&v| units.to_rad(v)).collect::<Vec<_>>());
                if i == 0 {
                    k
                } else {
                    k.at(t - t0)
                }
            })
            .collect();
        let path = match traj::plan(&limits, &keyframes, &reduced_options()) {
            Ok(path) => path,
            Err(e) => match split_longest(&chosen) {
                Some((at, i)) => {
                    chosen.insert(at, i);
                    continue;
                }
                None => return Err(e.to_string()),
            },
        };
        let mut worst = (0.0, None);
        for (i, (t, p)) in samples.iter().enumerate() {
            path.sample(t - t0, &mut state);
            let err = p.iter().zip(&state).fold(0.0f64, |m, (v, s)| {
                m.max((v - units.from_rad(s.position)).abs())
            });
            if err > worst.0 {
                worst = (err, Some(i));
            }
        }
        match worst {
            (e, Some(i)) if e > tolerance && !chosen.contains(&i) => {
                let at = chosen.partition_point(|&c| c < i);
                chosen.insert(at, i);
            }
            _ => break,
        }
    }
    Ok(chosen
        .iter()
        .map(|&i| (samples[i].0 - t0, samples[i].1.clone()))
        .collect())
}

/// What a take becomes: the keyframes of the motion file and what its
/// comments say about them.
#[derive(Debug, Clone, PartialEq)]
pub struct Taught {
    /// The keyframes, every joint in the robot's joint order; the first is
    /// the start (time 0).
    pub keyframes: Vec<TimedPose>,
    /// Whether the keyframes are written with their times (`at:`).
    pub timed: bool,
    /// Whether the file plays them with `interpolation: cubic` (a reduced
    /// recording, checked with that shape).
    pub cubic: bool,
    /// Comment lines for the file's header: how it was taught, and why it
    /// is timed or not.
    pub notes: Vec<String>,
}

impl Taught {
    /// Pose-and-pause: the starting pose, then each captured pose at the
    /// time it was captured (seconds from the start of the take), so that
    /// the motion replays at the pace it was taught. Where that pace breaks
    /// a limit of the robot, the keyframes are written untimed (each move as
    /// fast as the limits allow) and the file says why.
    pub fn paced(robot: &Robot, start: &[f64], captured: &[TimedPose]) -> Taught {
        let mut keyframes = vec![(0.0, start.to_vec())];
        keyframes.extend(captured.iter().cloned());
        let keyframes = merge_identical(keyframes, true);
        let mut notes = vec![format!(
            "pose-and-pause: the starting pose and {} captured pose{}",
            captured.len(),
            if captured.len() == 1 { "" } else { "s" }
        )];
        match paced_plan(robot, &keyframes).err() {
            None => {
                notes.push(
                    "`at` is when each pose was captured, s from the start: the motion replays at \
                     the pace it was taught"
                        .to_owned(),
                );
                Taught {
                    keyframes,
                    timed: true,
                    cubic: false,
                    notes,
                }
            }
            Some(reason) => {
                notes.push(format!(
                    "untimed: the pace it was taught at breaks a limit of the robot ({reason}); \
                     each move is as fast as the limits allow. Add `at: SECONDS` to time one"
                ));
                Taught {
                    keyframes: merge_identical(keyframes, false),
                    timed: false,
                    cubic: false,
                    notes,
                }
            }
        }
    }

    /// A continuous take: `samples` (every joint's angle at the control
    /// rate) trimmed of its idle ends (robot units: still within `still`),
    /// reduced to within `tolerance` (robot units), identical keyframes
    /// merged.
    ///
    /// # Errors
    /// As [`reduce`].
    pub fn continuous(
        robot: &Robot,
        samples: &[TimedPose],
        tolerance: f64,
        still: f64,
    ) -> Result<Taught, TeachError> {
        let trimmed = trim_idle(samples, still);
        let reduced = reduce(robot, trimmed, tolerance)?;
        let mut notes = vec![format!(
            "a continuous take reduced to within {tolerance} {}",
            robot.units
        )];
        if trimmed.len() < samples.len() {
            let idle = samples.len() - trimmed.len();
            notes.push(format!(
                "the idle time at its ends was trimmed ({idle} samples in which nothing moved)"
            ));
        }
        if let Some(s) = reduced.settle_s {
            notes.push(format!(
                "the take ended while the robot moved: its last pose is reached and held {s} s \
                 after the recording ends"
            ));
        }
        notes.push(
            "`at` is seconds from the first keyframe, as recorded; the spline through the \
             keyframes was checked to stay within the tolerance of the recording and the limits"
                .to_owned(),
        );
        Ok(Taught {
            keyframes: merge_identical(reduced.keyframes, true),
            timed: true,
            cubic: true,
            notes,
        })
    }
}

/// Whether `keyframes`, timed as captured, plan as `play` plans the written
/// file (the default interpolation, refused at a limit); the planner's
/// reason when not.
fn paced_plan(robot: &Robot, keyframes: &[TimedPose]) -> Result<(), String> {
    let motion = Motion {
        path: PathBuf::new(),
        robot_path: robot.path.clone(),
        units: robot.units,
        rate_hz: None,
        joints: robot.joints().map(|j| j.name.clone()).collect(),
        keyframes: keyframes
            .iter()
            .enumerate()
            .map(|(k, (t, p))| Keyframe {
                at: (k > 0).then_some(*t),
                planned_at: false,
                pose: None,
                tool: false,
                positions: p.clone(),
                grasps: Vec::new(),
                line: k + 1,
                column: 1,
            })
            .collect(),
        repeat: 1,
        on_limit: Default::default(),
        interpolation: Default::default(),
    };
    let (keys, options) = plan_input(&motion);
    traj::plan(&joint_limits(robot), &keys, &options)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

/// A commented motion file of `taught` for `robot`, angles in the robot's
/// units, whose `robot:` is `robot_file` as given: a built-in's name or a
/// path relative to where the motion is written
/// ([`motion_robot_field`](servobus_config::builtin::motion_robot_field)
/// makes one). Nothing is clamped: every pose was checked against the
/// limits ([`check_pose`]).
pub fn motion_yaml(robot: &Robot, robot_file: &Path, taught: &Taught) -> String {
    let mut y = String::new();
    let _ = writeln!(y, "# Taught by hand with `servobus teach`.");
    for note in &taught.notes {
        let _ = writeln!(y, "# {note}.");
    }
    let _ = writeln!(
        y,
        "# {} keyframes of every joint of `{}`; edit freely, then `servobus play` this file.",
        taught.keyframes.len(),
        robot.name
    );
    let _ = writeln!(
        y,
        "robot: {}",
        yaml_scalar(&robot_file.display().to_string())
    );
    let _ = writeln!(y, "units: {}", robot.units);
    if taught.cubic {
        let _ = writeln!(y, "interpolation: cubic");
    }
    let _ = writeln!(y, "keyframes:");
    for (k, (t, pose)) in taught.keyframes.iter().enumerate() {
        let mut line = String::from("  - ");
        if taught.timed && k > 0 {
            let _ = write!(line, "at: {t:.3}\n    ");
        }
        line.push_str("pose: {");
        for (i, (v, j)) in pose.iter().zip(robot.joints()).enumerate() {
            let sep = if i == 0 { "" } else { ", " };
            let _ = write!(line, "{sep}{}: {}", j.name, Fixed(*v, 2));
        }
        line.push('}');
        let _ = writeln!(y, "{line}");
    }
    y
}

/// `text` as a YAML scalar: as it is when it is plainly a path or a name,
/// else single-quoted (a space before `#`, a `: `, a leading `*` or `'` would
/// otherwise change what YAML reads).
fn yaml_scalar(text: &str) -> String {
    let plain = !text.is_empty()
        && text
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '/' | '-' | '<' | '>'))
        && !text.starts_with(['-', '<']);
    if plain {
        text.to_owned()
    } else {
        format!("'{}'", text.replace('\'', "''"))
    }
}
