//! A ROS 2 `trajectory_msgs/msg/JointTrajectory` made a timed chunk for
//! the stream ([`Chunk::timed`]): the points at `header.stamp` (zero: on
//! arrival) plus their `time_from_start`, on the node's stream clock.
//!
//! | in the message | what the chunk does |
//! |---|---|
//! | joint names | mapped by name; a joint not named keeps its target; an unknown or repeated name refuses the trajectory (`INVALID_JOINTS`) |
//! | positions only | straight pieces from point to point (as joint_trajectory_controller interpolates them) |
//! | positions and velocities | a cubic between two points that both have velocities, sampled every 20 ms or less |
//! | positions, velocities and accelerations | a quintic between two points that have all three |
//! | a point past a joint limit, a piece faster than a joint's velocity limit | refused with the joint, the point and the limit (`INVALID_GOAL`) |
//! | points already past on arrival | skipped; a trajectory wholly past is refused (`OLD_HEADER_TIMESTAMP`) |
//! | a start in the future | the joints hold where they are heading until it |
//! | the end | the last point is held [`SETTLE`] s more before the stream's timeout counts |
//!
//! The first point is reached from where the joints are heading: the
//! chunk replaces what is left of the current one from the commanded
//! state, so a trajectory sent mid-way joins smoothly. The chunk begins
//! with a point [`MARK_AGE`] before the arrival, at the commanded state:
//! already past when the loop takes the chunk, so it is skipped, while its
//! stamp (sent just before as an empty target's) keeps the stream's idea
//! of when messages arrive true even when the trajectory's first point is
//! seconds ahead. Efforts are ignored.

use servobus_robot::config::Units;
use servobus_robot::{Chunk, MAX_CHUNK_POINTS};

use crate::ros2::{FollowJointTrajectoryResult as Fjt, JointTrajectory, JointTrajectoryPoint};

/// How long before its arrival a trajectory's chunk begins, s: more than a
/// control period, so that its first point is past when the loop takes it.
pub(super) const MARK_AGE: f64 = 0.1;

/// How long the chunk holds the last point after it, s: the stream's
/// timeout counts from the chunk's end, so the joints settle on the last
/// point (a trajectory that ends moving is overshot a little) before they
/// stop waiting for more.
pub(super) const SETTLE: f64 = 1.0;

/// The longest spacing of the samples of a cubic or quintic piece, s.
const SPACING: f64 = 0.02;

/// Slack on the velocity limit for rounding.
const SPEED_SLACK: f64 = 1.001;

/// A joint's limits as trajectories are checked against them (rad, rad/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::node) struct Limits {
    /// Lowest position.
    pub min: f64,
    /// Highest position.
    pub max: f64,
    /// Velocity limit.
    pub max_velocity: f64,
}

/// The robot as ROS 2 messages address it.
#[derive(Debug, Clone)]
pub(in crate::node) struct RosRobot {
    /// Joint names, in the robot's order.
    pub names: Vec<String>,
    /// Per joint, its limits when the robot file is known.
    pub limits: Vec<Option<Limits>>,
    /// The robot file's units, for the reasons given to people.
    pub units: Units,
}

/// Why a trajectory was refused: a FollowJointTrajectory error code and a
/// reason for a person.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(in crate::node) struct Refusal {
    /// `INVALID_GOAL`, `INVALID_JOINTS` or `OLD_HEADER_TIMESTAMP`.
    pub code: i32,
    /// What is wrong, naming the point and joint.
    pub why: String,
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.why)
    }
}

fn invalid(why: String) -> Refusal {
    Refusal {
        code: Fjt::INVALID_GOAL,
        why,
    }
}

/// A trajectory ready for the stream.
#[derive(Debug, Clone, PartialEq)]
pub(in crate::node) struct Planned {
    /// The robot's index of each joint the trajectory names, in its order.
    pub joints: Vec<usize>,
    /// The chunk's stamps (stream clock, s), increasing.
    pub times: Vec<f64>,
    /// Per joint of `joints`, its position at each stamp, rad.
    pub positions: Vec<Vec<f64>>,
    /// When the trajectory starts (stream clock, s).
    pub start: f64,
    /// When its last point is due (stream clock, s).
    pub end: f64,
    /// Per joint of `joints`, the last point's position, rad.
    pub last: Vec<f64>,
}

impl Planned {
    /// The chunk, its joints named as `robot` names them.
    pub fn chunk(&self, robot: &RosRobot) -> Chunk {
        let joints = self
            .joints
            .iter()
            .zip(&self.positions)
            .map(|(&j, q)| (robot.names[j].clone(), q.clone()))
            .collect();
        Chunk::timed(self.times.clone(), joints)
    }
}

/// Where a trajectory arrives: the stream clock's now and the trajectory's
/// start on it (s), and where each joint of the robot is heading (rad;
/// `None` before the first cycle).
pub(in crate::node) struct Start<'a> {
    /// The arrival, stream clock.
    pub now: f64,
    /// `header.stamp` on the stream clock (`now` when it is zero).
    pub start: f64,
    /// The commanded position of a joint of the robot, by index.
    pub position: &'a dyn Fn(usize) -> Option<f64>,
}

/// Checks `traj` against `robot` and makes it a chunk arriving `from`.
///
/// # Errors
/// A [`Refusal`] naming what cannot be followed.
pub(in crate::node) fn plan(
    traj: &JointTrajectory,
    robot: &RosRobot,
    from: &Start<'_>,
) -> Result<Planned, Refusal> {
    let joints = joint_indices(&traj.joint_names, robot)?;
    let tfs = check_points(&traj.points, &traj.joint_names, robot, &joints)?;
    let (times, mut positions) = sample(&traj.points, &tfs, from.start, joints.len());
    check_speeds(&times, &positions, &tfs, from.start, robot, &joints)?;
    let end = from.start + tfs.last().copied().unwrap_or(0.0);
    // Points already past are skipped (the loop would skip them).
    let keep = times
        .iter()
        .position(|&t| t > from.now)
        .ok_or_else(|| Refusal {
            code: Fjt::OLD_HEADER_TIMESTAMP,
            why: format!(
                "the trajectory ended {:.3} s before it arrived (header.stamp plus the last \
             time_from_start)",
                from.now - end
            ),
        })?;
    let mut times = times[keep..].to_vec();
    for q in &mut positions {
        q.drain(..keep);
    }
    let last: Vec<f64> = positions
        .iter()
        .map(|q| q.last().copied().unwrap_or(0.0))
        .collect();
    times.push(end + SETTLE);
    for (q, l) in positions.iter_mut().zip(&last) {
        q.push(*l);
    }
    let heading: Vec<f64> = joints
        .iter()
        .zip(&positions)
        .map(|(&j, q)| (from.position)(j).unwrap_or(q[0]))
        .collect();
    // A start in the future: hold until it.
    if from.start > from.now + 1e-3 && times[0] > from.start + 1e-3 {
        times.insert(0, from.start);
        for (q, h) in positions.iter_mut().zip(&heading) {
            q.insert(0, *h);
        }
    }
    times.insert(0, from.now - MARK_AGE);
    for (q, h) in positions.iter_mut().zip(&heading) {
        q.insert(0, *h);
    }
    Ok(Planned {
        joints,
        times,
        positions,
        start: from.start,
        end,
        last,
    })
}

/// The robot's index of each joint named, in order.
fn joint_indices(names: &[String], robot: &RosRobot) -> Result<Vec<usize>, Refusal> {
    let refuse = |why: String| Refusal {
        code: Fjt::INVALID_JOINTS,
        why,
    };
    if names.is_empty() {
        return Err(refuse("the trajectory names no joint".into()));
    }
    let mut out: Vec<usize> = Vec::with_capacity(names.len());
    for name in names {
        let Some(j) = robot.names.iter().position(|n| n == name) else {
            return Err(refuse(format!(
                "no joint is named `{name}` (the robot's joints: {})",
                robot.names.join(", ")
            )));
        };
        if out.contains(&j) {
            return Err(refuse(format!("joint `{name}` is named twice")));
        }
        out.push(j);
    }
    Ok(out)
}

/// Checks every point: its sizes, its numbers, its time after the last
/// one's, and its positions within the limits. Returns each point's
/// `time_from_start`, s.
fn check_points(
    points: &[JointTrajectoryPoint],
    names: &[String],
    robot: &RosRobot,
    joints: &[usize],
) -> Result<Vec<f64>, Refusal> {
    let most = MAX_CHUNK_POINTS - 3;
    if points.is_empty() || points.len() > most {
        return Err(invalid(format!(
            "the trajectory has {} points: 1 to {most} are followed",
            points.len()
        )));
    }
    let n = names.len();
    let mut tfs = Vec::with_capacity(points.len());
    for (k, p) in points.iter().enumerate() {
        let sizes = [
            ("positions", p.positions.len(), false),
            ("velocities", p.velocities.len(), true),
            ("accelerations", p.accelerations.len(), true),
        ];
        for (what, len, may_be_empty) in sizes {
            if len != n && !(may_be_empty && len == 0) {
                return Err(invalid(format!(
                    "point {k} has {len} {what} for the trajectory's {n} joints"
                )));
            }
        }
        let values = p
            .positions
            .iter()
            .chain(&p.velocities)
            .chain(&p.accelerations);
        if values.clone().any(|v| !v.is_finite()) {
            return Err(invalid(format!(
                "point {k} holds a value that is not a number"
            )));
        }
        let d = p.time_from_start;
        let t = d.as_secs_f64();
        if d.sec < 0 || d.nanosec >= 1_000_000_000 {
            return Err(invalid(format!(
                "point {k}'s time_from_start ({}, {} ns) is not a time from the start",
                d.sec, d.nanosec
            )));
        }
        if let Some(&before) = tfs.last() {
            if t <= before {
                return Err(invalid(format!(
                    "point {k}'s time_from_start ({t} s) is not after point {}'s ({before} s)",
                    k - 1
                )));
            }
        }
        for (i, &q) in p.positions.iter().enumerate() {
            check_limit(q, joints[i], robot, &format!("point {k}"))?;
        }
        tfs.push(t);
    }
    Ok(tfs)
}

/// `q` (rad) within joint `j`'s limits, or the refusal saying `at` where.
fn check_limit(q: f64, j: usize, robot: &RosRobot, at: &str) -> Result<(), Refusal> {
    let Some(Some(l)) = robot.limits.get(j) else {
        return Ok(());
    };
    let u = robot.units;
    let past = if q < l.min - 1e-9 {
        Some(("below its minimum", l.min))
    } else if q > l.max + 1e-9 {
        Some(("above its maximum", l.max))
    } else {
        None
    };
    match past {
        Some((side, limit)) => Err(invalid(format!(
            "{at}: joint `{}` at {:.4} rad ({:.2} {}) is {side} {:.4} rad ({:.2} {})",
            robot.names[j],
            q,
            u.from_rad(q),
            u.name(),
            limit,
            u.from_rad(limit),
            u.name()
        ))),
        None => Ok(()),
    }
}

/// The samples of the path through `points` from `start`: the points
/// themselves, and inside each piece whose two ends have velocities, its
/// cubic (quintic with accelerations) every [`SPACING`] s or less.
/// Returns the stamps and, per joint, the positions.
fn sample(
    points: &[JointTrajectoryPoint],
    tfs: &[f64],
    start: f64,
    n: usize,
) -> (Vec<f64>, Vec<Vec<f64>>) {
    let curved = |k: usize| {
        k > 0 && !points[k - 1].velocities.is_empty() && !points[k].velocities.is_empty()
    };
    let curved_time: f64 = (1..points.len())
        .filter(|&k| curved(k))
        .map(|k| tfs[k] - tfs[k - 1])
        .sum();
    let room = MAX_CHUNK_POINTS.saturating_sub(3 + points.len()).max(1);
    let spacing = SPACING.max(curved_time / room as f64);
    let mut times = Vec::new();
    let mut positions = vec![Vec::new(); n];
    for (k, p) in points.iter().enumerate() {
        if curved(k) {
            let (a, b) = (&points[k - 1], p);
            let span = tfs[k] - tfs[k - 1];
            let steps = (span / spacing).ceil().max(1.0) as usize;
            for s in 1..steps {
                let s = s as f64 / steps as f64;
                times.push(start + tfs[k - 1] + s * span);
                for (i, q) in positions.iter_mut().enumerate() {
                    q.push(hermite(a, b, i, span, s));
                }
            }
        }
        times.push(start + tfs[k]);
        for (q, &p) in positions.iter_mut().zip(&p.positions) {
            q.push(p);
        }
    }
    (times, positions)
}

/// Joint `i`'s position at `s` (0..1) of the piece from `a` to `b`,
/// `span` s long: the cubic through both ends' positions and velocities,
/// the quintic when both also give accelerations.
fn hermite(a: &JointTrajectoryPoint, b: &JointTrajectoryPoint, i: usize, span: f64, s: f64) -> f64 {
    let (p0, p1) = (a.positions[i], b.positions[i]);
    let (v0, v1) = (a.velocities[i] * span, b.velocities[i] * span);
    let (s2, s3) = (s * s, s * s * s);
    if a.accelerations.is_empty() || b.accelerations.is_empty() {
        let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
        let h10 = s3 - 2.0 * s2 + s;
        let h01 = -2.0 * s3 + 3.0 * s2;
        let h11 = s3 - s2;
        return h00 * p0 + h10 * v0 + h01 * p1 + h11 * v1;
    }
    let (a0, a1) = (
        a.accelerations[i] * span * span,
        b.accelerations[i] * span * span,
    );
    let (s4, s5) = (s3 * s, s3 * s2);
    let h0 = 1.0 - 10.0 * s3 + 15.0 * s4 - 6.0 * s5;
    let h1 = s - 6.0 * s3 + 8.0 * s4 - 3.0 * s5;
    let h2 = 0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5;
    let h3 = 0.5 * s3 - s4 + 0.5 * s5;
    let h4 = -4.0 * s3 + 7.0 * s4 - 3.0 * s5;
    let h5 = 10.0 * s3 - 15.0 * s4 + 6.0 * s5;
    h0 * p0 + h1 * v0 + h2 * a0 + h3 * a1 + h4 * v1 + h5 * p1
}

/// Every sample within the limits, and no piece between two samples
/// faster than its joint's velocity limit; refusals name the points the
/// piece lies between.
fn check_speeds(
    times: &[f64],
    positions: &[Vec<f64>],
    tfs: &[f64],
    start: f64,
    robot: &RosRobot,
    joints: &[usize],
) -> Result<(), Refusal> {
    // The point a sample's piece ends at.
    let point_of = |t: f64| tfs.iter().position(|&p| start + p >= t - 1e-9).unwrap_or(0);
    let u = robot.units;
    for (q, &j) in positions.iter().zip(joints) {
        let Some(Some(l)) = robot.limits.get(j) else {
            continue;
        };
        for (w, t) in q.windows(2).zip(times.windows(2)) {
            let k = point_of(t[1]);
            check_limit(
                w[1],
                j,
                robot,
                &format!("between points {} and {k}", k.max(1) - 1),
            )?;
            let speed = (w[1] - w[0]).abs() / (t[1] - t[0]);
            if speed > l.max_velocity * SPEED_SLACK {
                return Err(invalid(format!(
                    "joint `{}` would move at {:.3} rad/s ({:.1} {}/s) from point {} to point {k}: \
                     its velocity limit is {:.3} rad/s ({:.1} {}/s)",
                    robot.names[j],
                    speed,
                    u.from_rad(speed),
                    u.name(),
                    k.max(1) - 1,
                    l.max_velocity,
                    u.from_rad(l.max_velocity),
                    u.name()
                )));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
