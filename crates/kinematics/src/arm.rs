//! Inverse kinematics of an arm: damped least squares (Levenberg-Marquardt)
//! on the chain from the base to a named frame, inside the joint limits,
//! started from the previous solution so that a move stays on one branch
//! (no elbow or wrist flips).
//!
//! The target is a position and, optionally, the pitch and roll of the
//! frame (as in its roll-pitch-yaw angles): the part of the orientation a
//! 5-DOF arm such as the SO-101 can choose. The yaw is whatever the arm's
//! pan gives.

use nalgebra::{Isometry3, Matrix6, Point3, SMatrix, SVector, Unit, UnitQuaternion, Vector3};

use crate::error::IkError;
use crate::geometry::Geometry;
use crate::leg::within;

/// The most joints an arm chain may have.
pub const MAX_DOF: usize = 7;

/// Position tolerance of a solution, mm.
const POS_TOL: f64 = 1e-4;
/// Orientation tolerance of a solution, rad.
const ROT_TOL: f64 = 1e-6;
/// The length that weighs a radian of orientation error against a
/// millimetre of position error (about a forearm's length).
const ROT_WEIGHT_MM: f64 = 100.0;
/// Iterations before giving up on one start.
const MAX_ITER: usize = 200;
/// The largest joint step of one iteration, rad (keeps a move on its branch).
const MAX_STEP: f64 = 0.3;
/// Damping: start, floor and the ceiling past which the search stops.
const LAMBDA_START: f64 = 1.0;
const LAMBDA_MIN: f64 = 1e-6;
const LAMBDA_MAX: f64 = 1e8;
/// Restart poses tried when the previous angles lead nowhere: a grid of
/// [`GRID`], then points spread over the joints' ranges.
const RESTARTS: usize = 118;
const GRID: usize = 54;
/// One Halton base per joint.
const PRIMES: [usize; MAX_DOF] = [2, 3, 5, 7, 11, 13, 17];

type Jacobian = SMatrix<f64, 6, MAX_DOF>;
type Angles = SVector<f64, MAX_DOF>;
type Residual = SVector<f64, 6>;

/// Where an arm's frame should go: a position in the base frame (mm) and,
/// when given, its pitch and roll (radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmTarget {
    /// Position, mm.
    pub xyz: Point3<f64>,
    /// Pitch of the frame (rotation about y in its roll-pitch-yaw), rad.
    pub pitch: Option<f64>,
    /// Roll of the frame (rotation about x in its roll-pitch-yaw), rad.
    pub roll: Option<f64>,
}

/// The solver for one arm frame, built once from the geometry.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmIk {
    frame: String,
    joints: Vec<usize>,
    names: Vec<String>,
    origins: Vec<Isometry3<f64>>,
    axes: Vec<Unit<Vector3<f64>>>,
    limits: Vec<(f64, f64)>,
    /// The frame on the last joint's link.
    tool: Isometry3<f64>,
    /// No target farther than this from the first joint's origin can be
    /// reached: the sum of the chain's link lengths, mm.
    reach: f64,
}

/// How one start of the search ended.
struct Search {
    q: Angles,
    e: Residual,
}

impl ArmIk {
    /// The solver for the named frame `frame` (say `tool`).
    ///
    /// # Errors
    /// [`IkError::UnknownFrame`]; [`IkError::Unsupported`] for a frame on
    /// the base or behind more than [`MAX_DOF`] joints.
    pub fn new(model: &Geometry, frame: &str) -> Result<Self, IkError> {
        let f = model
            .frame_index(frame)
            .ok_or_else(|| IkError::UnknownFrame {
                frame: frame.to_owned(),
            })?;
        let joints = model.chain_to_frame(f);
        if joints.is_empty() || joints.len() > MAX_DOF {
            return Err(IkError::Unsupported {
                frame: frame.to_owned(),
                why: "an arm frame sits behind 1 to 7 joints",
            });
        }
        let chain: Vec<&crate::geometry::Joint> =
            joints.iter().map(|&i| &model.joints[i]).collect();
        Ok(ArmIk {
            frame: frame.to_owned(),
            names: chain.iter().map(|j| j.name.clone()).collect(),
            origins: chain.iter().map(|j| j.origin).collect(),
            axes: chain.iter().map(|j| j.axis).collect(),
            limits: chain.iter().map(|j| j.limits).collect(),
            tool: model.frames[f].origin,
            reach: chain
                .iter()
                .skip(1)
                .map(|j| j.origin.translation.vector.norm())
                .sum::<f64>()
                + model.frames[f].origin.translation.vector.norm(),
            joints,
        })
    }

    /// The chain's joints (robot order indices), base first: the order of
    /// the angles [`ArmIk::solve`] takes and gives.
    pub fn joints(&self) -> &[usize] {
        &self.joints
    }

    /// The frame's pose at chain angles `q` (radians).
    pub fn frame_pose(&self, q: &[f64]) -> Isometry3<f64> {
        let mut t = Isometry3::identity();
        for (k, (o, a)) in self.origins.iter().zip(&self.axes).enumerate() {
            t = t * o * UnitQuaternion::from_axis_angle(a, q.get(k).copied().unwrap_or(0.0));
        }
        t * self.tool
    }

    /// Angles of the chain (radians, base first, into `out`) that put the
    /// frame at `target`, starting from `previous` (the chain's current or
    /// last commanded angles). Allocates nothing. From a `previous` near
    /// the answer (a step of a move) the answer stays on its branch; when
    /// the search from `previous` finds nothing, it starts again from poses
    /// spread over the joints' ranges, and that answer may lie on another
    /// branch (a caller moving in steps should check the step's size).
    ///
    /// # Errors
    /// [`IkError::JointLimit`] naming a joint the answer would push past a
    /// limit, [`IkError::Unreachable`] with the distance short, or
    /// [`IkError::Singular`] when the position is reached but not the
    /// orientation.
    pub fn solve(
        &self,
        target: &ArmTarget,
        previous: &[f64],
        out: &mut [f64],
    ) -> Result<(), IkError> {
        let n = self.joints.len();
        let mut start = Angles::zeros();
        for k in 0..n {
            let v = previous.get(k).copied().unwrap_or(0.0);
            let v = if v.is_finite() { v } else { 0.0 };
            start[k] = v.clamp(self.limits[k].0, self.limits[k].1);
        }
        let toward = target.xyz.y.atan2(target.xyz.x);
        let base = self.origins[0].translation.vector;
        if (target.xyz.coords - base).norm() > self.reach {
            // Farther than the links laid end to end: no restart can help.
            return Err(self.reason(&self.search(target, start, false)));
        }
        for bounded in [true, false] {
            let first = self.search(target, start, bounded);
            let mut found = converged(&first.e).then_some(first.q);
            // The previous angles led nowhere: start again from spread-out
            // poses (the first joint turned towards the target or away from
            // it, the next three bent either way).
            for m in 0..RESTARTS {
                if found.is_some() {
                    break;
                }
                let s = self.search(target, self.restart(m, toward), bounded);
                found = converged(&s.e).then_some(s.q);
            }
            match (found, bounded) {
                (Some(q), true) => return self.write(&q, out),
                // An answer found without limits: inside them once each
                // angle is taken a turn round if need be, or else name the
                // joint furthest out.
                (Some(q), false) => {
                    let mut wrapped = q;
                    for (k, &(lo, hi)) in self.limits.iter().enumerate() {
                        wrapped[k] = wrap_into(q[k], lo, hi);
                    }
                    let inside = (0..self.joints.len()).all(|k| within(wrapped[k], self.limits[k]));
                    return if inside {
                        self.write(&wrapped, out)
                    } else {
                        Err(self.beyond(&wrapped))
                    };
                }
                (None, false) => return Err(self.reason(&first)),
                (None, true) => {}
            }
        }
        Err(IkError::Singular {
            what: "no answer found",
        })
    }

    /// The joint of `q` (an answer without limits) furthest beyond its
    /// limits.
    fn beyond(&self, q: &Angles) -> IkError {
        let mut worst = (0, 0.0, 0.0);
        for (k, &(lo, hi)) in self.limits.iter().enumerate() {
            let a = q[k];
            let out = (lo - a).max(a - hi);
            if out > worst.1 {
                worst = (k, out, a);
            }
        }
        let (k, _, angle) = worst;
        IkError::JointLimit {
            joint: self.names[k].clone(),
            angle,
            min: self.limits[k].0,
            max: self.limits[k].1,
        }
    }

    fn write(&self, q: &Angles, out: &mut [f64]) -> Result<(), IkError> {
        for (k, o) in out.iter_mut().enumerate().take(self.joints.len()) {
            *o = q[k];
        }
        Ok(())
    }

    /// Restart pose `m` of [`RESTARTS`]. The first [`GRID`]: bit 0 turns
    /// the first joint towards the target (`toward`, rad about the base's
    /// z) or away from it; the rest, read in base 3, put each of the next
    /// three joints at its middle or 0.6 of its half-range either side.
    /// Then points of a Halton sequence spread over the whole range of
    /// every joint.
    fn restart(&self, m: usize, toward: f64) -> Angles {
        let mut q = Angles::zeros();
        if m >= GRID {
            for (k, &(lo, hi)) in self.limits.iter().enumerate() {
                let (lo, hi) = if lo.is_finite() && hi.is_finite() {
                    (lo, hi)
                } else {
                    (-std::f64::consts::PI, std::f64::consts::PI)
                };
                q[k] = lo + (hi - lo) * halton(m - GRID + 1, PRIMES[k]);
            }
            return q;
        }
        for (k, &(lo, hi)) in self.limits.iter().enumerate() {
            let (mid, half) = if lo.is_finite() && hi.is_finite() {
                (0.5 * (lo + hi), 0.5 * (hi - lo))
            } else {
                (0.0, 1.0)
            };
            q[k] = match k {
                0 if m & 1 == 0 => toward,
                0 => toward + std::f64::consts::PI,
                1..=3 => {
                    mid + 0.6 * half * (((m >> 1) / 3usize.pow(k as u32 - 1)) % 3) as f64
                        - 0.6 * half
                }
                _ => mid,
            };
            q[k] = wrap_into(q[k], lo, hi).clamp(lo, hi);
        }
        q
    }

    /// Levenberg-Marquardt from `q`, inside the limits when `bounded`.
    fn search(&self, target: &ArmTarget, mut q: Angles, bounded: bool) -> Search {
        let n = self.joints.len();
        let mut jac = Jacobian::zeros();
        let mut e = self.residual(target, &q, &mut jac);
        let mut lambda = LAMBDA_START;
        let mut trial_jac = Jacobian::zeros();
        for _ in 0..MAX_ITER {
            if converged(&e) {
                break;
            }
            let jjt: Matrix6<f64> = jac * jac.transpose() + Matrix6::identity() * (lambda * lambda);
            let Some(chol) = jjt.cholesky() else {
                lambda *= 4.0;
                continue;
            };
            let mut dq: Angles = jac.transpose() * chol.solve(&e);
            let biggest = dq.amax();
            if biggest > MAX_STEP {
                dq *= MAX_STEP / biggest;
            }
            let mut trial = q;
            for k in 0..n {
                trial[k] = q[k] + dq[k];
                if bounded {
                    trial[k] = trial[k].clamp(self.limits[k].0, self.limits[k].1);
                }
            }
            let te = self.residual(target, &trial, &mut trial_jac);
            if te.norm_squared() < e.norm_squared() {
                q = trial;
                e = te;
                jac = trial_jac;
                lambda = (lambda * 0.5).max(LAMBDA_MIN);
            } else {
                lambda *= 4.0;
                if lambda > LAMBDA_MAX {
                    break;
                }
            }
        }
        Search { q, e }
    }

    /// The weighted residual (position mm; orientation rad x
    /// [`ROT_WEIGHT_MM`]) at `q`, and the Jacobian into `jac`.
    fn residual(&self, target: &ArmTarget, q: &Angles, jac: &mut Jacobian) -> Residual {
        let n = self.joints.len();
        let mut origins = [Vector3::zeros(); MAX_DOF];
        let mut axes = [Vector3::zeros(); MAX_DOF];
        let mut t = Isometry3::identity();
        for k in 0..n {
            t = t * self.origins[k] * UnitQuaternion::from_axis_angle(&self.axes[k], q[k]);
            origins[k] = t.translation.vector;
            axes[k] = t.rotation * self.axes[k].into_inner();
        }
        let tool = t * self.tool;
        let p = tool.translation.vector;
        let ep = target.xyz.coords - p;
        // Pitch and roll fix which direction of the frame points straight
        // up (yaw turns about that direction): `up`, in the frame, must
        // point along the base's z. With pitch alone, the frame's x axis
        // must have the right elevation.
        let z = Vector3::z();
        let (r0, p0, _) = tool.rotation.euler_angles();
        let up = match (target.pitch, target.roll) {
            (None, None) => None,
            (Some(pitch), None) => Some((Vector3::x(), Some(-pitch.sin()))),
            (pitch, roll) => {
                let pr =
                    UnitQuaternion::from_euler_angles(roll.unwrap_or(r0), pitch.unwrap_or(p0), 0.0);
                Some((pr.inverse() * z, None))
            }
        };
        let (v, eo) = match up {
            None => (Vector3::zeros(), Vector3::zeros()),
            Some((local, None)) => {
                let v = tool.rotation * local;
                (v, (z - v) * ROT_WEIGHT_MM)
            }
            Some((local, Some(height))) => {
                let v = tool.rotation * local;
                (v, Vector3::new(0.0, 0.0, height - v.z) * ROT_WEIGHT_MM)
            }
        };
        let only_z = matches!(up, Some((_, Some(_))));
        jac.fill(0.0);
        for k in 0..n {
            let lin = axes[k].cross(&(p - origins[k]));
            jac.fixed_view_mut::<3, 1>(0, k).copy_from(&lin);
            if up.is_some() {
                let mut dv = axes[k].cross(&v) * ROT_WEIGHT_MM;
                if only_z {
                    dv.x = 0.0;
                    dv.y = 0.0;
                }
                jac.fixed_view_mut::<3, 1>(3, k).copy_from(&dv);
            }
        }
        Residual::new(ep.x, ep.y, ep.z, eo.x, eo.y, eo.z)
    }

    /// Why a search without limits that did not converge failed.
    fn reason(&self, s: &Search) -> IkError {
        let short = s.e.fixed_rows::<3>(0).norm();
        if short > POS_TOL {
            return IkError::Unreachable { short };
        }
        IkError::Singular {
            what: "the orientation cannot be reached from here",
        }
    }

    /// The frame this solver places.
    pub fn frame(&self) -> &str {
        &self.frame
    }

    /// How far chain angles `q` (radians, base first) are from a singular
    /// pose: the smallest singular value of the frame position's Jacobian,
    /// mm per radian. It is the speed (mm/s) at which the frame can move in
    /// its worst direction for joint speeds of one radian a second in all;
    /// 0 where a direction cannot be moved at all (the arm stretched
    /// straight or folded flat, the frame on the first joint's axis).
    /// Allocates nothing.
    pub fn dexterity(&self, q: &[f64]) -> f64 {
        let mut jac = Jacobian::zeros();
        let mut angles = Angles::zeros();
        for (k, a) in angles.iter_mut().enumerate().take(self.joints.len()) {
            *a = q.get(k).copied().unwrap_or(0.0);
        }
        let free = ArmTarget {
            xyz: Point3::origin(),
            pitch: None,
            roll: None,
        };
        self.residual(&free, &angles, &mut jac);
        let lin = jac.fixed_rows::<3>(0);
        // The eigenvalues of J J^T (3 x 3) are the squared singular values.
        let jjt = lin * lin.transpose();
        jjt.symmetric_eigenvalues().min().max(0.0).sqrt()
    }

    /// Whether chain angles `q` are inside every joint's limits.
    pub fn within_limits(&self, q: &[f64]) -> bool {
        q.iter().zip(&self.limits).all(|(&v, &l)| within(v, l))
    }
}

fn converged(e: &Residual) -> bool {
    e.fixed_rows::<3>(0).norm() < POS_TOL && e.fixed_rows::<3>(3).norm() < ROT_TOL * ROT_WEIGHT_MM
}

/// `a`, or `a` a turn either way, whichever lies in `[lo, hi]`; else the
/// one of them nearest the range.
fn wrap_into(a: f64, lo: f64, hi: f64) -> f64 {
    let turn = 2.0 * std::f64::consts::PI;
    let a = a.rem_euclid(turn);
    let a = if a > std::f64::consts::PI {
        a - turn
    } else {
        a
    };
    let outside = |v: f64| (lo - v).max(v - hi).max(0.0);
    [a, a - turn, a + turn]
        .into_iter()
        .min_by(|x, y| outside(*x).total_cmp(&outside(*y)))
        .unwrap_or(a)
}

/// Element `i` of the Halton sequence in `base`, in [0, 1).
fn halton(mut i: usize, base: usize) -> f64 {
    let mut f = 1.0;
    let mut r = 0.0;
    while i > 0 {
        f /= base as f64;
        r += f * (i % base) as f64;
        i /= base;
    }
    r
}
