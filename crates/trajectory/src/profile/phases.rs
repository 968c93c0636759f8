//! Constant-jerk phases: a profile as a list of (duration, jerk) that turns
//! into polynomial pieces.

use super::ramp::Ramp;
use crate::piece::Piece;
use crate::{JointLimits, JointState};

/// A sixth, to multiply by (a division costs several multiplications).
pub(crate) const SIXTH: f64 = 1.0 / 6.0;

/// Up to 12 constant-jerk phases: enough for a stop (3) followed by a full
/// segment profile (7).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Phases {
    pub n: usize,
    pub dt: [f64; 12],
    /// Jerk of each phase. For a jerk-free (trapezoidal) phase change the
    /// acceleration is set directly through `acc`.
    pub jerk: [f64; 12],
    /// Acceleration at the start of each phase (only used when the jerk
    /// bound is infinite: then acceleration jumps between phases).
    pub acc: [f64; 12],
}

impl Phases {
    #[inline]
    pub const fn new() -> Self {
        Phases {
            n: 0,
            dt: [0.0; 12],
            jerk: [0.0; 12],
            acc: [0.0; 12],
        }
    }

    #[inline]
    pub fn push(&mut self, dt: f64, jerk: f64, acc: f64) {
        if dt > 0.0 && self.n < 12 {
            self.dt[self.n] = dt;
            self.jerk[self.n] = jerk;
            self.acc[self.n] = acc;
            self.n += 1;
        }
    }

    /// A ramp in direction `s` (+1 speeds up in the positive direction).
    #[inline]
    pub(super) fn push_ramp(&mut self, r: &Ramp, s: f64, j: f64) {
        let jj = if j.is_finite() { s * j } else { 0.0 };
        self.push(r.tj, jj, 0.0);
        self.push(r.ta, 0.0, s * r.peak);
        self.push(r.tj, -jj, s * r.peak);
    }

    /// [`emit`](Self::emit) from state `x` at time `t`, not mirrored, with a
    /// finite jerk exactly when `lim` has one.
    pub fn emit_from(
        &self,
        t: f64,
        x: &JointState,
        lim: &JointLimits,
        out: &mut Vec<Piece>,
    ) -> (f64, f64, f64, f64) {
        let finite = lim.max_jerk.is_some();
        self.emit(t, x.position, x.velocity, x.acceleration, 1.0, finite, out)
    }

    /// Integrates the phases from state `x`, mirrored by `dir`, for at most
    /// `limit` seconds (allocation-free). Returns the time integrated and
    /// the state reached.
    #[inline]
    pub fn advance(
        &self,
        x: &JointState,
        dir: f64,
        finite_jerk: bool,
        limit: f64,
    ) -> (f64, f64, f64, f64) {
        let start = (x.position, x.velocity, x.acceleration);
        self.integrate::<true>(0.0, start, dir, finite_jerk, limit, |_| {})
    }

    /// Appends the pieces, starting at time `t` in state `(p, v, a)`, the
    /// whole profile mirrored by `dir` (+1 or -1). Returns the end time and
    /// state. With a finite jerk the acceleration is integrated (continuous);
    /// with an infinite one it is taken from `acc`.
    #[allow(clippy::too_many_arguments)] // a state (t, p, v, a) plus options
    pub fn emit(
        &self,
        t: f64,
        p: f64,
        v: f64,
        a: f64,
        dir: f64,
        finite_jerk: bool,
        out: &mut Vec<Piece>,
    ) -> (f64, f64, f64, f64) {
        let each = |piece| out.push(piece);
        let (t, p, v, a) = self.integrate::<false>(t, (p, v, a), dir, finite_jerk, 0.0, each);
        // Without a jerk limit the profile ends at rest in acceleration
        // (even with no phase at all).
        (t, p, v, if finite_jerk { a } else { 0.0 })
    }

    /// The one integration of [`advance`](Self::advance) and
    /// [`emit`](Self::emit): from time `t0` in state `(p, v, a)`, mirrored
    /// by `dir`, for at most `limit` s when `LIMITED` (else to the end:
    /// the planners' case, with no test per phase), handing `each` the
    /// piece of every phase begun. Returns the end time and state. Without
    /// a jerk limit the acceleration of a phase is its `acc`, and zero
    /// after a whole one.
    #[inline(always)]
    fn integrate<const LIMITED: bool>(
        &self,
        t0: f64,
        (mut p, mut v, mut a): (f64, f64, f64),
        dir: f64,
        finite_jerk: bool,
        limit: f64,
        mut each: impl FnMut(Piece),
    ) -> (f64, f64, f64, f64) {
        let mut t = t0;
        for k in 0..self.n {
            let mut dt = self.dt[k];
            if LIMITED {
                if t - t0 >= limit {
                    break;
                }
                dt = dt.min(limit - (t - t0));
            }
            let jk = dir * self.jerk[k];
            if !finite_jerk {
                a = dir * self.acc[k];
            }
            each(Piece::jerk(t, dt, p, v, a, jk));
            p += dt * (v + dt * (0.5 * a + dt * jk * SIXTH));
            v += dt * (a + 0.5 * dt * jk);
            a += dt * jk;
            t += dt;
            if !finite_jerk && (!LIMITED || dt == self.dt[k]) {
                a = 0.0;
            }
        }
        (t, p, v, a)
    }
}
