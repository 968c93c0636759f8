//! Stretching a segment's profile to a longer duration by lowering its
//! cruise speed: closed forms first, a safeguarded Newton search otherwise.

use super::ramp::Acc;
use super::{Profile, Segment1};

impl Segment1 {
    /// How far a cruise at `vc > 0` is from a duration of `t`, as
    /// `vc (T(vc) - t)` (the sign of `T - t`), and its derivative with
    /// respect to `vc`, for the stretching search. Written as
    /// `T vc = d + sum((vc - v_i) dur_i / 2)` (the cruise covers what the
    /// ramps, point-symmetric, do not), it needs no division, and its
    /// derivative `sum(H_i') - t` with `H_i' = dur_i / 2 + |vc - v_i|
    /// dur_i' / 2` stays accurate where a ramp vanishes (`vc` near `v_i`,
    /// where `dur_i'` is unbounded but `|vc - v_i| dur_i'` is not). Nearly
    /// linear in `vc` (`d - t vc` plus the ramps' share), so Newton needs
    /// few steps.
    #[inline(always)]
    fn excess(&self, vc: f64, t: f64, c: &Acc) -> (f64, f64) {
        let mut h = self.d - t * vc;
        let mut dh = -t;
        for v in [self.v0, self.v1] {
            let e = vc - v;
            let dv = e.abs();
            // `dur` and `dv * d dur / d dv`.
            let (dur, ddv) = if dv >= c.regime {
                (dv * c.inv_a + c.k, dv * c.inv_a)
            } else {
                let r = 2.0 * (dv * c.j).sqrt() * c.inv_j;
                (r, 0.5 * r)
            };
            h += 0.5 * e * dur;
            dh += 0.5 * (dur + ddv);
        }
        (h, dh)
    }

    /// The profile of duration exactly `t >= fastest.duration`, stretched by
    /// lowering the cruise speed. `fastest` is the time-optimal profile or
    /// any feasible one with a lower cruise speed (the upper bound of
    /// [`fastest_bounds`](Self::fastest_bounds)): the search only needs a
    /// cruise speed whose duration is at most `t`.
    pub fn stretched(&self, acc: &Acc, fastest: Profile, t: f64) -> Profile {
        if t <= fastest.duration * (1.0 + 1e-12) || fastest.vc <= 0.0 {
            return Profile {
                vc: fastest.vc,
                duration: t.max(fastest.duration),
            };
        }
        if self.d <= 0.0 {
            // Nothing to cover: only possible at rest; hold.
            return Profile {
                vc: 0.0,
                duration: t,
            };
        }
        let mut vc = None;
        if self.v0 == 0.0 && self.v1 == 0.0 {
            // Rest to rest with a constant-acceleration phase:
            // vc^2 / a + (a / j - t) vc + d = 0, smaller root.
            let b = t - acc.k;
            let disc = b * b - 4.0 * self.d * acc.inv_a;
            if disc >= 0.0 {
                // The smaller root, in the form without cancellation
                // (the product of the roots is a * d).
                let x = 2.0 * self.d / (b + disc.sqrt());
                if x >= acc.regime && x <= fastest.vc {
                    vc = Some(x);
                }
            }
        }
        // Every ramp reaching the acceleration limit (always so without a
        // jerk limit) makes the duration equation a quadratic: its root,
        // where the ramps are indeed long, is the answer. Elsewhere it is
        // still a close first guess (long-formula ramps are slower than
        // short ones, jerk-free ones faster: the answer lies between).
        // (Not needed where the rest-to-rest form has answered.)
        let model = if vc.is_none() {
            self.model_root(acc.inv_a, acc.k, t, fastest.vc)
                .or_else(|| self.model_root(acc.inv_a, 0.0, t, fastest.vc))
        } else {
            None
        };
        if vc.is_none() {
            vc = model.filter(|&x| {
                (x - self.v0).abs() >= acc.regime
                    && (x - self.v1).abs() >= acc.regime
                    && self.d - self.g(x, acc).1 >= -1e-12 * self.d
            });
        }
        let vc = match vc {
            Some(x) => x,
            None => {
                // `excess` is positive below the answer and at most 0 at
                // `fastest.vc`: the bracket is `[0, fastest.vc]`.
                let f = |vc: f64| self.excess(vc, t, acc);
                let guess = model.unwrap_or(self.d / t);
                solve(f, 0.0, fastest.vc, guess, false)
            }
        };
        Profile { vc, duration: t }
    }

    /// The cruise speed in `(0, hi]` of duration `t` if every ramp took
    /// `|w - u| / a + k` (`a = 1 / inv_a`; `k = a / j`: the exact duration
    /// of a ramp reaching the acceleration limit; `k = 0`: jerk-free), if
    /// there is one. With `s_i = sign(vc - v_i)` the duration equation
    /// `t vc = d + sum((vc - v_i) dur_i / 2)` is the quadratic
    /// `A vc^2 + B vc + C = 0`, `A = (s0 + s1) / 2a`,
    /// `B = k - t - (s0 v0 + s1 v1) / a`,
    /// `C = d + (s0 v0^2 + s1 v1^2) / 2a - (v0 + v1) k / 2`. The duration
    /// decreasing with `vc`, the signs follow from comparing it with `t` at
    /// `vc = v_i`, so only one quadratic is solved.
    fn model_root(&self, inv_a: f64, k: f64, t: f64, hi: f64) -> Option<f64> {
        let (v0, v1, d) = (self.v0, self.v1, self.d);
        let h = 0.5 * inv_a;
        // `vc * (duration(vc) - t)`: positive below the root.
        let excess = |vc: f64| {
            let (e0, e1) = (vc - v0, vc - v1);
            d + (e0 * e0.abs() + e1 * e1.abs()) * h + 0.5 * k * (e0 + e1) - t * vc
        };
        let side = |v: f64| {
            if v <= 0.0 || (v < hi && excess(v) > 0.0) {
                1.0
            } else {
                -1.0
            }
        };
        let (s0, s1) = (side(v0), side(v1));
        let qa = (s0 + s1) * h;
        let qb = k - t - (s0 * v0 + s1 * v1) * inv_a;
        let qc = d + (s0 * v0 * v0 + s1 * v1 * v1) * h - 0.5 * k * (v0 + v1);
        let ok = |vc: f64| {
            vc > 0.0
                && vc <= hi * (1.0 + 1e-12)
                && s0 * (vc - v0) >= -1e-12 * hi
                && s1 * (vc - v1) >= -1e-12 * hi
        };
        let pick = |vc: f64| ok(vc).then(|| vc.min(hi));
        if qa == 0.0 {
            return pick(-qc / qb);
        }
        let disc = qb * qb - 4.0 * qa * qc;
        if disc < 0.0 {
            return None;
        }
        let q = -0.5 * (qb + qb.signum() * disc.sqrt());
        pick(q / qa).or_else(|| pick(qc / q))
    }
}

/// Safeguarded Newton iteration on a function with one sign change in the
/// bracket `[lo, hi]`: `increasing` tells the sign convention (`f(lo) <= 0
/// <= f(hi)` when true, the reverse otherwise). Falls back to bisection
/// whenever a Newton step leaves the bracket, so it always converges.
/// Stops after a Newton step smaller than `1e-5` relative: convergence is
/// quadratic by then, so the error left is about its square times the
/// function's relative curvature, which the stretching's (nearly linear in
/// the cruise speed) keeps below 1: some 1e-10 relative at most, an
/// evaluation sooner than waiting for rounding.
fn solve(
    f: impl Fn(f64) -> (f64, f64),
    mut lo: f64,
    mut hi: f64,
    x0: f64,
    increasing: bool,
) -> f64 {
    // (Not `clamp`, which panics on a NaN bound.)
    let mut x = x0.max(lo).min(hi);
    for _ in 0..200 {
        let (fx, dfx) = f(x);
        if fx == 0.0 {
            return x;
        }
        if (fx < 0.0) == increasing {
            lo = x;
        } else {
            hi = x;
        }
        let mut nx = x - fx / dfx;
        let mut newton = true;
        if !(nx > lo && nx < hi) {
            newton = false;
            nx = 0.5 * (lo + hi);
        }
        let step = (nx - x).abs();
        if (newton && step <= 1e-5 * nx.abs())
            || step <= 1e-13 * nx.abs()
            || hi - lo <= 1e-13 * hi.abs()
        {
            return nx;
        }
        x = nx;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::super::Phases;
    use super::*;

    /// Stretched profiles of segments of every kind (rest to rest, equal
    /// and unequal boundary speeds, short and long ramps: with `a = 3` and
    /// `j = 10` a speed change is short below `a^2 / j = 0.9`) cover their
    /// distance in exactly the duration asked, ending at their end speed,
    /// down to a cruise far below both boundary speeds. Each boundary
    /// speed can stop within half the distance, as the planners' speeds
    /// at keyframes can (the condition for a profile of every duration).
    #[test]
    fn the_stretching_search_meets_every_duration_and_distance() {
        let acc = Acc::of(&crate::JointLimits::new(2.0, 3.0, Some(10.0)));
        let segments = [
            (1.3, 0.4, 0.2),
            (0.05, 0.0, 0.0),
            (2.5, 0.0, 0.0),
            (0.8, 0.5, 0.5),
            (3.0, 1.5, 0.1),
            (1.0, 0.05, 1.2),
            (4.0, 1.9, 1.8),
        ];
        let (mut below, mut long) = (false, false);
        for (d, v0, v1) in segments {
            let s = Segment1 { d, v0, v1 };
            let f = s.fastest(&acc);
            for k in [1.0, 1.001, 1.1, 1.5, 2.0, 4.0, 20.0] {
                let t = f.duration * k;
                let p = s.stretched(&acc, f, t);
                assert!(p.vc > 0.0 && p.vc <= f.vc * (1.0 + 1e-12), "{d} {k}");
                below |= p.vc < v0.min(v1);
                long |= (p.vc - v0).abs() > 0.9 || (p.vc - v1).abs() > 0.9;
                let mut ph = Phases::new();
                s.phases(&acc, p, &mut ph);
                let mut out = Vec::new();
                let (te, x, v, a) = ph.emit(0.0, 0.0, v0, 0.0, 1.0, true, &mut out);
                assert!((te - t).abs() < 1e-9 * t, "{d} {k}: {te} != {t}");
                assert!((x - d).abs() < 1e-9 * d.max(1.0), "{d} {k}: {x}");
                assert!((v - v1).abs() < 1e-9 && a.abs() < 1e-9, "{d} {k}");
            }
        }
        assert!(below && long);
    }
}
