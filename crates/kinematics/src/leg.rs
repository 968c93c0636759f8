//! Closed-form inverse kinematics of a 3-DOF leg: a coxa turning about its
//! frame's z axis, then a femur and a tibia turning about parallel axes
//! (their frames' y axes) in the vertical plane the coxa points.

use std::f64::consts::PI;

use nalgebra::{Isometry3, Point3, Vector2};

use crate::error::IkError;
use crate::geometry::Geometry;

/// How close to 1 a unit component must be to count as aligned with it.
const ALIGNED: f64 = 1e-9;
/// How close to the coxa's axis a foot counts as on it (where the coxa's
/// angle is undefined), mm.
const SINGULAR_MM: f64 = 1.0;
/// How close to straight or folded flat the knee counts as at a
/// singularity, rad (1 deg: nearer, the joint speeds a foot's move needs
/// grow without bound).
const KNEE_MARGIN_RAD: f64 = std::f64::consts::PI / 180.0;

/// A leg's closed-form solver, built once from the geometry.
#[derive(Debug, Clone, PartialEq)]
pub struct LegIk {
    /// Coxa, femur, tibia (robot order indices).
    joints: [usize; 3],
    names: [String; 3],
    limits: [(f64, f64); 3],
    /// The coxa's frame before it turns, in the base frame.
    hip_inv: Isometry3<f64>,
    /// +1 when the coxa turns about +z.
    s1: f64,
    /// The femur's axis in the coxa's (x, z) plane.
    femur_at: Vector2<f64>,
    /// +1 when femur (tibia) turns raise x towards z (axis -y).
    s2: f64,
    s3: f64,
    /// Femur to tibia, tibia to foot, in their (x, z) planes.
    v1: Vector2<f64>,
    v2: Vector2<f64>,
    /// Their lengths and directions (rad from x towards z).
    l1: f64,
    l2: f64,
    b1: f64,
    b2: f64,
}

fn sign_of(component: f64) -> Option<f64> {
    if (component.abs() - 1.0).abs() < ALIGNED {
        Some(component.signum())
    } else {
        None
    }
}

/// Rotates `v` in the (x, z) plane by `phi` (x towards z).
fn rot(v: Vector2<f64>, phi: f64) -> Vector2<f64> {
    let (s, c) = phi.sin_cos();
    Vector2::new(v.x * c - v.y * s, v.x * s + v.y * c)
}

/// `a` wrapped into (-pi, pi] (a few turns at most: sums of angles).
fn wrap(mut a: f64) -> f64 {
    if !a.is_finite() {
        return a;
    }
    while a > PI {
        a -= 2.0 * PI;
    }
    while a <= -PI {
        a += 2.0 * PI;
    }
    a
}

impl LegIk {
    /// The solver for the foot frame called `foot`.
    ///
    /// # Errors
    /// [`IkError::UnknownFrame`]; [`IkError::Unsupported`] when the chain
    /// to it is not coxa (on the base, about z), femur and tibia (about y,
    /// offsets in the x-z plane, no rotation between them).
    pub fn new(model: &Geometry, foot: &str) -> Result<Self, IkError> {
        let unsupported = |why| IkError::Unsupported {
            frame: foot.to_owned(),
            why,
        };
        let f = model
            .frame_index(foot)
            .ok_or_else(|| IkError::UnknownFrame {
                frame: foot.to_owned(),
            })?;
        let chain = model.chain_to_frame(f);
        let [c, fe, t] = chain[..] else {
            return Err(unsupported("a leg is three joints from the base"));
        };
        let (jc, jf, jt) = (&model.joints[c], &model.joints[fe], &model.joints[t]);
        let s1 = sign_of(jc.axis.z).ok_or_else(|| unsupported("the coxa must turn about z"))?;
        let s2 = sign_of(-jf.axis.y).ok_or_else(|| unsupported("the femur must turn about y"))?;
        let s3 = sign_of(-jt.axis.y).ok_or_else(|| unsupported("the tibia must turn about y"))?;
        let planar = |iso: &Isometry3<f64>, turns: bool| {
            let v = iso.translation.vector;
            let straight = !turns || iso.rotation.angle() < ALIGNED;
            (v.y.abs() < ALIGNED && straight).then(|| Vector2::new(v.x, v.z))
        };
        let femur_at = planar(&jf.origin, true)
            .ok_or_else(|| unsupported("the femur must sit in the coxa's x-z plane"))?;
        let v1 = planar(&jt.origin, true)
            .ok_or_else(|| unsupported("the tibia must sit in the femur's x-z plane"))?;
        let v2 = planar(&model.frames[f].origin, false)
            .ok_or_else(|| unsupported("the foot must sit in the tibia's x-z plane"))?;
        Ok(LegIk {
            joints: [c, fe, t],
            names: [jc.name.clone(), jf.name.clone(), jt.name.clone()],
            limits: [jc.limits, jf.limits, jt.limits],
            hip_inv: jc.origin.inverse(),
            s1,
            femur_at,
            s2,
            s3,
            l1: v1.norm(),
            l2: v2.norm(),
            b1: v1.y.atan2(v1.x),
            b2: v2.y.atan2(v2.x),
            v1,
            v2,
        })
    }

    /// The coxa, femur and tibia (indices in the robot's joint order).
    pub fn joints(&self) -> [usize; 3] {
        self.joints
    }

    /// Coxa, femur and tibia angles (radians) that put the foot at `target`
    /// (base frame, mm). Of the two knee solutions inside the limits, the
    /// one nearer `previous` (so a move never flips the knee); reaching
    /// back past the coxa axis only when reaching out has none. Allocates
    /// nothing.
    ///
    /// # Errors
    /// [`IkError::Unreachable`] with the distance short,
    /// [`IkError::Singular`] at the foot within 1 mm of the coxa axis or the
    /// knee within 1 deg of straight or folded flat, [`IkError::JointLimit`]
    /// naming the joint.
    pub fn solve(&self, target: &Point3<f64>, previous: [f64; 3]) -> Result<[f64; 3], IkError> {
        let p = self.hip_inv * target;
        let r = p.x.hypot(p.y);
        if r < SINGULAR_MM {
            return Err(IkError::Singular {
                what: "the foot is on the coxa's axis",
            });
        }
        // The leg may reach out over its foot or back past its coxa axis.
        let ahead = p.y.atan2(p.x);
        let sides = [(ahead, r), (wrap(ahead + PI), -r)];
        let (l1, l2, b1, b2) = (self.l1, self.l2, self.b1, self.b2);
        let mut best: Option<([f64; 3], f64)> = None;
        let mut violation: Option<(usize, f64)> = None;
        let mut short = f64::INFINITY;
        let mut singular = false;
        for (yaw, reach) in sides {
            // Reach back past the coxa axis only when reaching out cannot.
            if best.is_some() {
                break;
            }
            let t = Vector2::new(reach, p.z) - self.femur_at;
            let d = t.norm();
            let miss = (d - (l1 + l2)).max((l1 - l2).abs() - d);
            if miss > 0.0 {
                short = short.min(miss);
                continue;
            }
            let cos_g = ((d * d - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)).clamp(-1.0, 1.0);
            let gamma = cos_g.acos();
            if !(KNEE_MARGIN_RAD..=PI - KNEE_MARGIN_RAD).contains(&gamma) {
                singular = true;
                continue;
            }
            let toward = t.y.atan2(t.x);
            for g in [gamma, -gamma] {
                let alpha = g - b2 + b1;
                let w = self.v1 + rot(self.v2, alpha);
                let phi = toward - w.y.atan2(w.x);
                let q = [
                    wrap(yaw * self.s1),
                    wrap(phi) * self.s2,
                    wrap(alpha) * self.s3,
                ];
                if let Some(k) = (0..3).find(|&k| !within(q[k], self.limits[k])) {
                    violation.get_or_insert((k, q[k]));
                    continue;
                }
                let dist: f64 = (0..3).map(|k| (q[k] - previous[k]).powi(2)).sum();
                if best.is_none_or(|(_, d0)| dist < d0) {
                    best = Some((q, dist));
                }
            }
        }
        if best.is_none() && violation.is_none() {
            return Err(if singular {
                IkError::Singular {
                    what: "the leg is stretched straight or folded flat",
                }
            } else {
                IkError::Unreachable { short }
            });
        }
        match (best, violation) {
            (Some((q, _)), _) => Ok(q),
            (None, Some((k, angle))) => Err(IkError::JointLimit {
                joint: self.names[k].clone(),
                angle,
                min: self.limits[k].0,
                max: self.limits[k].1,
            }),
            (None, None) => Err(IkError::Singular {
                what: "no knee solution",
            }),
        }
    }
}

/// `q` inside `(min, max)`, with a hair of tolerance for rounding.
pub(crate) fn within(q: f64, (min, max): (f64, f64)) -> bool {
    const EPS: f64 = 1e-9;
    q >= min - EPS && q <= max + EPS
}
