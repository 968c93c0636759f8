//! The legs of a legged robot, found by their feet (`foot_<leg>` frames),
//! and body moves with the feet planted: the body goes from one pose to
//! another along a [`PoseLine`] while every foot keeps its place on the
//! ground, each leg solved in closed form.

use nalgebra::{Isometry3, Point3};
use thiserror::Error;

use crate::error::IkError;
use crate::geometry::{Geometry, Poses};
use crate::leg::LegIk;
use crate::line::PoseLine;

/// The prefix of a foot frame's name; the rest is the leg's name.
pub const FOOT_PREFIX: &str = "foot_";

/// One leg: its name, its foot frame and its solver.
#[derive(Debug, Clone, PartialEq)]
struct Leg {
    name: String,
    foot: usize,
    ik: LegIk,
}

/// Every leg of a robot (every `foot_<leg>` frame), in the order of the
/// frames' names.
#[derive(Debug, Clone, PartialEq)]
pub struct Legs {
    model: Geometry,
    legs: Vec<Leg>,
}

/// A leg that cannot take its foot where a move needs it.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("at {t:.3} s, leg `{leg}`: {reason}")]
pub struct LegError {
    /// Time from the start of the move, s.
    pub t: f64,
    /// The leg.
    pub leg: String,
    /// Why.
    pub reason: IkError,
}

/// One sample of a legged move: its time from the move's start and every
/// joint's angle (radians, robot order).
#[derive(Debug, Clone, PartialEq)]
pub struct PoseSample {
    /// Time from the start of the move, s.
    pub t: f64,
    /// Every joint of the robot, radians; joints of no leg as they were.
    pub q: Vec<f64>,
}

impl Legs {
    /// The legs of `model`: one per frame named `foot_<leg>`.
    ///
    /// # Errors
    /// [`IkError::UnknownFrame`] (`foot_<leg>`) when there is none, or the
    /// [`LegIk::new`] error of a leg that is not coxa, femur and tibia.
    pub fn new(model: &Geometry) -> Result<Self, IkError> {
        let mut legs = Vec::new();
        for f in 0..model.frame_count() {
            let Some(name) = model.frame_name(f) else {
                continue;
            };
            let Some(leg) = name.strip_prefix(FOOT_PREFIX) else {
                continue;
            };
            legs.push(Leg {
                name: leg.to_owned(),
                foot: f,
                ik: LegIk::new(model, name)?,
            });
        }
        if legs.is_empty() {
            return Err(IkError::UnknownFrame {
                frame: format!("{FOOT_PREFIX}<leg>"),
            });
        }
        Ok(Legs {
            model: model.clone(),
            legs,
        })
    }

    /// How many legs.
    pub fn len(&self) -> usize {
        self.legs.len()
    }

    /// Whether there are none (never, once built).
    pub fn is_empty(&self) -> bool {
        self.legs.is_empty()
    }

    /// Leg `i`'s name (its foot frame without `foot_`).
    pub fn name(&self, i: usize) -> Option<&str> {
        self.legs.get(i).map(|l| l.name.as_str())
    }

    /// The geometry the legs belong to.
    pub fn model(&self) -> &Geometry {
        &self.model
    }

    /// Where every foot is (body frame, mm) at joint angles `q` (radians,
    /// robot order), into `out` (one per leg), using `poses` as scratch.
    pub fn feet(&self, q: &[f64], poses: &mut Poses, out: &mut [Point3<f64>]) {
        self.model.forward(q, poses);
        for (leg, o) in self.legs.iter().zip(out.iter_mut()) {
            if let Some(p) = poses.frame(leg.foot) {
                *o = Point3::from(p.translation.vector);
            }
        }
    }

    /// Puts every foot at `feet` (body frame, mm; one per leg), the legs'
    /// joints in `q` (radians, robot order) solved from their values
    /// there (so no knee flips); other joints are left as they are.
    ///
    /// # Errors
    /// The leg (its index) and why it cannot reach.
    pub fn place(&self, feet: &[Point3<f64>], q: &mut [f64]) -> Result<(), (usize, IkError)> {
        for (i, (leg, target)) in self.legs.iter().zip(feet).enumerate() {
            let j = leg.ik.joints();
            let previous = j.map(|k| q.get(k).copied().unwrap_or(0.0));
            let got = leg.ik.solve(target, previous).map_err(|e| (i, e))?;
            for (k, v) in j.into_iter().zip(got) {
                if let Some(slot) = q.get_mut(k) {
                    *slot = v;
                }
            }
        }
        Ok(())
    }

    /// Places the feet at `world` (mm, the ground's frame) seen from a
    /// body at `body` (its pose in that frame), into `q`.
    ///
    /// # Errors
    /// As [`Legs::place`], with the time `t` for the message.
    pub fn place_from(
        &self,
        body: &Isometry3<f64>,
        world: &[Point3<f64>],
        t: f64,
        q: &mut [f64],
    ) -> Result<(), LegError> {
        let inv = body.inverse();
        let local: Vec<Point3<f64>> = world.iter().map(|w| inv * w).collect();
        self.place(&local, q).map_err(|(i, reason)| LegError {
            t,
            leg: self.legs[i].name.clone(),
            reason,
        })
    }

    /// The body moves along `line` (its pose relative to the ground's
    /// frame, in which the feet are planted at `world`) with the time law
    /// `s_of_t` over `duration_s`, sampled every `step_s` at most; `start`
    /// holds every joint's angle before the move (radians, robot order).
    ///
    /// # Errors
    /// A [`LegError`]: the time and the leg that cannot follow.
    pub fn body_move(
        &self,
        line: &PoseLine,
        world: &[Point3<f64>],
        start: &[f64],
        duration_s: f64,
        s_of_t: impl Fn(f64) -> f64,
        step_s: f64,
    ) -> Result<Vec<PoseSample>, LegError> {
        let steps = (duration_s / step_s).ceil().max(1.0) as usize;
        let mut q = start.to_vec();
        let mut out = Vec::with_capacity(steps + 1);
        out.push(PoseSample {
            t: 0.0,
            q: q.clone(),
        });
        for k in 1..=steps {
            let t = duration_s * k as f64 / steps as f64;
            let s = if k == steps { 1.0 } else { s_of_t(t) };
            self.place_from(&line.at(s), world, t, &mut q)?;
            out.push(PoseSample { t, q: q.clone() });
        }
        Ok(out)
    }
}
