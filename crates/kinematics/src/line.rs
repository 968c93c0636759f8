//! Straight moves in space: a frame that goes from one pose to another
//! along a straight line while its orientation turns along the shortest
//! arc (slerp), and the arm angles that follow it, sampled densely enough
//! that moving the joints straight from one sample to the next keeps the
//! frame within a tolerance of the line.

use nalgebra::{Isometry3, Point3, Translation3};
use thiserror::Error;

use crate::arm::{ArmIk, ArmTarget, MAX_DOF};
use crate::error::IkError;

/// How a pose's orientation is weighed against its position when a move
/// turns more than it travels: a radian counts as this many millimetres.
pub const TURN_WEIGHT_MM: f64 = 100.0;

/// A straight move between two poses: the position along the segment, the
/// orientation along the shortest arc between the two.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseLine {
    from: Isometry3<f64>,
    to: Isometry3<f64>,
}

impl PoseLine {
    /// The move from `from` to `to`.
    pub fn new(from: Isometry3<f64>, to: Isometry3<f64>) -> Self {
        PoseLine { from, to }
    }

    /// The pose at fraction `s` of the way (0: `from`, 1: `to`).
    pub fn at(&self, s: f64) -> Isometry3<f64> {
        let s = s.clamp(0.0, 1.0);
        let p = self
            .from
            .translation
            .vector
            .lerp(&self.to.translation.vector, s);
        // Opposite orientations have no shortest arc: turn about any axis.
        let r = self
            .from
            .rotation
            .try_slerp(&self.to.rotation, s, 1e-9)
            .unwrap_or_else(|| self.from.rotation.nlerp(&self.to.rotation, s));
        Isometry3::from_parts(Translation3::from(p), r)
    }

    /// The distance the position travels, mm.
    pub fn length_mm(&self) -> f64 {
        (self.to.translation.vector - self.from.translation.vector).norm()
    }

    /// The angle the orientation turns, rad.
    pub fn turn_rad(&self) -> f64 {
        self.from.rotation.angle_to(&self.to.rotation)
    }

    /// The move's length as one number: the travel or the turn
    /// ([`TURN_WEIGHT_MM`] per radian), whichever is longer, mm.
    pub fn extent_mm(&self) -> f64 {
        self.length_mm().max(self.turn_rad() * TURN_WEIGHT_MM)
    }

    /// How far `p` is from the segment, mm.
    pub fn distance_mm(&self, p: &Point3<f64>) -> f64 {
        let a = self.from.translation.vector;
        let d = self.to.translation.vector - a;
        let len2 = d.norm_squared();
        let s = if len2 > 0.0 {
            ((p.coords - a).dot(&d) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p.coords - (a + d * s)).norm()
    }
}

/// Which parts of the orientation a tool line holds the arm to (those the
/// keyframe gives; the others follow from the arm).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Held {
    /// Hold the pitch along the slerped orientation.
    pub pitch: bool,
    /// Hold the roll.
    pub roll: bool,
}

/// How densely a line is sampled and what counts as too close to a
/// singular pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineOptions {
    /// Moving the joints straight between two samples keeps the frame
    /// within this distance of the line, mm.
    pub tolerance_mm: f64,
    /// The first sampling, before samples are added where the tolerance
    /// needs them: at most this far apart in time, s.
    pub max_step_s: f64,
    /// A sample whose [`ArmIk::dexterity`] is below this (mm/rad) is near
    /// a singular pose, and the line is refused there.
    pub min_dexterity: f64,
    /// The largest change of a joint between two samples once the
    /// tolerance holds, rad: more means the arm flips branch.
    pub max_jump_rad: f64,
    /// The most samples the line may take (the first included): the
    /// sampling stops with [`IkError::TooManySamples`] before it makes
    /// more, so a tiny tolerance or step cannot exhaust memory.
    pub max_samples: usize,
}

/// The default of [`LineOptions::max_samples`]: an hour's line at 50 ms
/// is 72,000 samples; this leaves fourteen times that for the tolerance.
pub const MAX_LINE_SAMPLES: usize = 1_000_000;

impl Default for LineOptions {
    fn default() -> Self {
        LineOptions {
            tolerance_mm: 0.2,
            max_step_s: 0.05,
            min_dexterity: 10.0,
            max_jump_rad: 0.35,
            max_samples: MAX_LINE_SAMPLES,
        }
    }
}

/// One sample of a line: its time from the line's start and the chain's
/// angles (radians, base first).
#[derive(Debug, Clone, PartialEq)]
pub struct LineSample {
    /// Time from the start of the line, s.
    pub t: f64,
    /// Fraction of the line covered.
    pub s: f64,
    /// The arm chain's angles, radians ([`ArmIk::joints`] order).
    pub q: Vec<f64>,
}

/// The sampled line and the closest it comes to a singular pose.
#[derive(Debug, Clone, PartialEq)]
pub struct LinePlan {
    /// The samples, the first at the line's start (t = 0) and the last at
    /// its end.
    pub samples: Vec<LineSample>,
    /// The smallest [`ArmIk::dexterity`] of any sample, mm/rad.
    pub min_dexterity: f64,
}

/// Why a line cannot be followed, and where on it.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{along_mm:.1} mm along the line: {reason}")]
pub struct LineError {
    /// How far along the line the problem is, mm.
    pub along_mm: f64,
    /// What goes wrong there.
    pub reason: IkError,
}

/// Deepest halving of one interval while looking for the tolerance.
const MAX_SPLITS: usize = 12;

/// Angles that take the arm's frame along `line` from chain angles `start`
/// (radians, base first; the frame should be at the line's start there).
/// `s_of_t` is the time law: the fraction of the line covered `t` seconds
/// after the start, over `duration_s`. Samples come at most
/// `options.max_step_s` apart, and closer where moving the joints straight
/// from one to the next would take the frame further than
/// `options.tolerance_mm` from the line.
///
/// # Errors
/// A [`LineError`] saying how far along the line: the reason of the arm's
/// inverse kinematics (unreachable, a joint limit), or
/// [`IkError::Singular`] where the line passes near a singular pose or
/// the arm would have to flip.
pub fn sample_line(
    arm: &ArmIk,
    line: &PoseLine,
    held: Held,
    start: &[f64],
    duration_s: f64,
    s_of_t: impl Fn(f64) -> f64,
    options: &LineOptions,
) -> Result<LinePlan, LineError> {
    let solver = LineSolver {
        arm,
        line,
        held,
        options,
    };
    let steps = (duration_s / options.max_step_s).ceil().max(1.0);
    let too_many = IkError::TooManySamples {
        limit: options.max_samples,
    };
    // NaN (a bad duration or step) is refused too.
    if steps.is_nan() || steps >= options.max_samples as f64 {
        return Err(LineError {
            along_mm: 0.0,
            reason: too_many,
        });
    }
    // Below the limit, a usize.
    let steps = steps as usize;
    let n = arm.joints().len();
    let mut min_dexterity = arm.dexterity(start);
    let mut samples = vec![LineSample {
        t: 0.0,
        s: 0.0,
        q: start[..n.min(start.len())].to_vec(),
    }];
    for k in 1..=steps {
        let t = duration_s * k as f64 / steps as f64;
        let s = if k == steps { 1.0 } else { s_of_t(t) };
        // Fill in between the last sample and this one until straight
        // joint moves keep to the line.
        let mut pending = vec![(t, s)];
        while let Some(&(t1, s1)) = pending.last() {
            let prev = samples.last().map_or(0.0, |p| p.t);
            let q0 = samples.last().map(|p| p.q.clone()).unwrap_or_default();
            let q1 = solver.solve(s1, &q0)?;
            let depth_left = pending.len() < MAX_SPLITS;
            if depth_left && !solver.straight_enough(&q0, &q1, &s_of_t, prev, t1) {
                let tm = 0.5 * (prev + t1);
                pending.push((tm, s_of_t(tm)));
                continue;
            }
            min_dexterity = min_dexterity.min(solver.check_step(s1, &q0, &q1)?);
            if samples.len() >= options.max_samples {
                return Err(solver.error(s1, too_many.clone()));
            }
            samples.push(LineSample {
                t: t1,
                s: s1,
                q: q1,
            });
            pending.pop();
        }
    }
    Ok(LinePlan {
        samples,
        min_dexterity,
    })
}

struct LineSolver<'a> {
    arm: &'a ArmIk,
    line: &'a PoseLine,
    held: Held,
    options: &'a LineOptions,
}

impl LineSolver<'_> {
    fn target(&self, s: f64) -> ArmTarget {
        let pose = self.line.at(s);
        let (roll, pitch, _) = pose.rotation.euler_angles();
        ArmTarget {
            xyz: Point3::from(pose.translation.vector),
            pitch: self.held.pitch.then_some(pitch),
            roll: self.held.roll.then_some(roll),
        }
    }

    fn solve(&self, s: f64, previous: &[f64]) -> Result<Vec<f64>, LineError> {
        let mut out = [0.0; MAX_DOF];
        let n = self.arm.joints().len();
        self.arm
            .solve(&self.target(s), previous, &mut out[..n])
            .map_err(|e| self.error(s, e))?;
        Ok(out[..n].to_vec())
    }

    /// Refuses a step from `q0` to `q1` (at `s` along the line) that flips
    /// the arm to another branch or passes too close to a singular pose;
    /// the arm's dexterity at `q1` otherwise.
    fn check_step(&self, s: f64, q0: &[f64], q1: &[f64]) -> Result<f64, LineError> {
        let n = self.arm.joints().len();
        if (0..n).any(|k| (q1[k] - q0[k]).abs() > self.options.max_jump_rad) {
            return Err(self.error(
                s,
                IkError::Singular {
                    what: "the arm would have to flip to another branch",
                },
            ));
        }
        let d = self.arm.dexterity(q1);
        if d < self.options.min_dexterity {
            return Err(self.error(
                s,
                IkError::Singular {
                    what: "the line passes too close to a singular pose of the arm",
                },
            ));
        }
        Ok(d)
    }

    fn error(&self, s: f64, reason: IkError) -> LineError {
        LineError {
            along_mm: s * self.line.length_mm(),
            reason,
        }
    }

    /// Whether the joints moving straight from `q0` (at `t0`) to `q1` (at
    /// `t1`) keep the frame near the line: checked at the quarter points
    /// against where the line is at that time.
    fn straight_enough(
        &self,
        q0: &[f64],
        q1: &[f64],
        s_of_t: &impl Fn(f64) -> f64,
        t0: f64,
        t1: f64,
    ) -> bool {
        let mut q = [0.0; MAX_DOF];
        [0.25, 0.5, 0.75].into_iter().all(|f| {
            for (k, v) in q.iter_mut().enumerate().take(q0.len()) {
                *v = q0[k] + (q1[k] - q0[k]) * f;
            }
            let at = self.arm.frame_pose(&q[..q0.len()]);
            let want = self.line.at(s_of_t(t0 + (t1 - t0) * f));
            let off = (at.translation.vector - want.translation.vector).norm();
            off <= 0.5 * self.options.tolerance_mm
        })
    }
}
