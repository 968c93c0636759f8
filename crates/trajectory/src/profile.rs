//! One joint, one segment: jerk-limited velocity profiles in closed form.
//!
//! A segment moves a distance `d >= 0` (after normalising the direction to
//! positive) from speed `v0 >= 0` to speed `v1 >= 0`, with zero acceleration
//! at both ends. Its profile is
//!
//! ```text
//!  v ^        vc ____________
//!    |   ramp A /            \ ramp B
//!  v0|_________/              \________ v1
//!    +----------------------------------> t
//!       (S-curve)   cruise     (S-curve)
//! ```
//!
//! where each ramp is an S-curve velocity change (jerk, constant
//! acceleration, jerk; the middle phase vanishes for small changes and the
//! jerk phases vanish without a jerk limit). The whole family is indexed by
//! the cruise speed `vc`: the time-optimal profile has the largest feasible
//! `vc`, and a longer duration `T` (to finish together with a slower joint)
//! is met by the unique smaller `vc` whose duration is `T` — the profile is
//! stretched, never padded with idling at the end. The duration is strictly
//! decreasing in `vc` wherever the cruise time is non-negative, which makes
//! the search a safe one-dimensional root find.
//!
//! Velocity never changes sign inside a segment, so a joint never overshoots
//! the segment's end positions.

use crate::{JointLimits, JointState};

/// A velocity ramp of size `dv >= 0`: jerk phases of `tj`, a constant
/// acceleration phase of `ta`, reaching acceleration `peak`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Ramp {
    pub tj: f64,
    pub ta: f64,
    pub peak: f64,
}

impl Ramp {
    /// The shortest ramp changing the speed by `dv` under `a` and `j`
    /// (`j` may be infinite).
    #[inline]
    pub fn new(dv: f64, a: f64, j: f64) -> Ramp {
        if dv <= 0.0 {
            Ramp {
                tj: 0.0,
                ta: 0.0,
                peak: 0.0,
            }
        } else if dv * j >= a * a {
            Ramp {
                tj: a / j,
                ta: dv / a - a / j,
                peak: a,
            }
        } else {
            let tj = (dv / j).sqrt();
            Ramp {
                tj,
                ta: 0.0,
                peak: j * tj,
            }
        }
    }

    #[inline]
    pub fn duration(&self) -> f64 {
        2.0 * self.tj + self.ta
    }
}

/// Acceleration and jerk bounds with the reciprocals the solvers need,
/// computed once per call instead of dividing in every iteration.
#[derive(Debug, Clone, Copy)]
struct Acc {
    inv_a: f64,
    j: f64,
    /// `1 / j` (0 without a jerk limit).
    inv_j: f64,
    /// `a / j`: duration of a full jerk phase (0 without a jerk limit).
    k: f64,
    /// `a^2 / j`: the speed change above which a ramp has a constant
    /// acceleration phase.
    regime: f64,
}

impl Acc {
    fn new(a: f64, j: f64) -> Self {
        Acc {
            inv_a: 1.0 / a,
            j,
            inv_j: 1.0 / j,
            k: a / j,
            regime: a * a / j,
        }
    }
}

/// Duration and distance of the ramp from `u` to `w` and their derivatives
/// with respect to `w`. Distance is `(u + w) / 2 * duration` because an
/// S-curve ramp is point-symmetric about its midpoint.
#[inline(always)]
fn leg(u: f64, w: f64, c: &Acc) -> (f64, f64, f64, f64) {
    let dv = (w - u).abs();
    let sgn = if w >= u { 1.0 } else { -1.0 };
    let (dur, ddur) = if dv >= c.regime {
        (dv * c.inv_a + c.k, c.inv_a)
    } else if dv > 0.0 {
        // `s = sqrt(dv j)`: jerk phases of `s / j` each, and
        // `d(2 sqrt(dv / j)) / d dv = 1 / s`.
        let s = (dv * c.j).sqrt();
        (2.0 * s * c.inv_j, 1.0 / s)
    } else {
        (0.0, f64::INFINITY)
    };
    let ddur_dw = sgn * ddur;
    let dist = 0.5 * (u + w) * dur;
    let ddist = 0.5 * dur + 0.5 * (u + w) * ddur_dw;
    (dur, dist, ddur_dw, ddist)
}

/// A normalised segment: distance `d >= 0`, boundary speeds `v0, v1 >= 0`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Segment1 {
    pub d: f64,
    pub v0: f64,
    pub v1: f64,
}

/// What [`Segment1::fastest_bounds`] knows without root finding.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Bounds {
    /// At most the time-optimal duration.
    pub lower: f64,
    /// A feasible profile at least as long as the time-optimal one.
    pub upper: Profile,
    /// `upper` is the time-optimal profile itself.
    pub exact: bool,
}

/// The chosen profile of a segment: its cruise speed and duration.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Profile {
    pub vc: f64,
    pub duration: f64,
}

/// Largest `vc` with `vc * ramp_duration(vc) <= dist`: the peak speed of a
/// rest-to-rest move of `dist` (closed form).
#[inline]
pub(crate) fn rest_peak(dist: f64, lim: &JointLimits) -> f64 {
    let (vm, a, j) = (lim.max_velocity, lim.max_acceleration, lim.jerk());
    if dist <= 0.0 {
        return 0.0;
    }
    if dist >= vm * Ramp::new(vm, a, j).duration() {
        return vm;
    }
    // Constant-acceleration regime: vc (vc / a + a / j) = dist.
    let k = a / j;
    let vc = 0.5 * a * (-k + (k * k + 4.0 * dist / a).sqrt());
    if vc * j >= a * a {
        return vc.min(vm);
    }
    // Pure jerk regime: dist = 2 vc sqrt(vc / j).
    (0.25 * dist * dist * j).cbrt().min(vm)
}

impl Segment1 {
    /// The segment covering `d` (either sign) from speed `vin` to `vout`,
    /// normalised to a positive direction. The planners give a keyframe
    /// either no speed or one in the direction of motion, so the speeds
    /// become non-negative.
    pub fn between(d: f64, vin: f64, vout: f64) -> Segment1 {
        Segment1 {
            d: d.abs(),
            v0: vin.abs(),
            v1: vout.abs(),
        }
    }

    /// A feasible profile no longer than `limit` (a cruise speed for
    /// [`stretched`](Self::stretched)), if the time-optimal one is no
    /// longer: from the bounds when they decide, else solved.
    pub fn fits(&self, lim: &JointLimits, limit: f64) -> Option<Profile> {
        let b = self.fastest_bounds(lim);
        if b.upper.duration <= limit {
            Some(b.upper)
        } else if b.exact || b.lower > limit {
            None
        } else {
            Some(self.fastest(lim)).filter(|f| f.duration <= limit)
        }
    }

    /// Total ramp distance and its derivative at cruise speed `vc`.
    #[inline(always)]
    fn g(&self, vc: f64, c: &Acc) -> (f64, f64, f64, f64) {
        let (ta, da, dta, dda) = leg(self.v0, vc, c);
        let (tb, db, dtb, ddb) = leg(self.v1, vc, c);
        (ta + tb, da + db, dta + dtb, dda + ddb)
    }

    /// Duration at cruise speed `vc > 0` and its derivative.
    #[inline(always)]
    fn time(&self, vc: f64, c: &Acc) -> (f64, f64) {
        let (t, g, dt, dg) = self.g(vc, c);
        let rest = self.d - g;
        let inv = 1.0 / vc;
        (t + rest * inv, dt - (dg + rest * inv) * inv)
    }

    /// Duration at cruise speed `vc = 1 / u` and its derivative with
    /// respect to `u`, for the stretching search. Written as
    /// `T vc = d + sum((vc - v_i) dur_i / 2)` (the cruise covers what the
    /// ramps, point-symmetric, do not), whose derivative
    /// `dT/dvc = (sum(H_i') - T) / vc` with `H_i' = dur_i / 2 + |vc - v_i|
    /// dur_i' / 2` stays accurate where a ramp vanishes (`vc` near `v_i`,
    /// where `dur_i'` is unbounded but `|vc - v_i| dur_i'` is not).
    #[inline(always)]
    fn time_of_inv(&self, u: f64, c: &Acc) -> (f64, f64) {
        let vc = 1.0 / u;
        let mut h = self.d;
        let mut dh = 0.0;
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
        let t = h * u;
        // dT/du = -vc^2 dT/dvc = (T - sum(H_i')) vc.
        (t, (t - dh) * vc)
    }

    /// The time-optimal profile. Precondition: the ramps alone fit, i.e.
    /// `g(max(v0, v1)) <= d` (the planner caps via speeds to ensure it).
    pub fn fastest(&self, lim: &JointLimits) -> Profile {
        let (vm, a, j) = (lim.max_velocity, lim.max_acceleration, lim.jerk());
        let acc = Acc::new(a, j);
        let vc = match self.fastest_closed(lim, &acc) {
            Ok(vc) => vc,
            // The long-ramp root (outside its regime) is a good start.
            Err(guess) => self.fastest_root(&acc, self.v0.max(self.v1).min(vm), vm, guess),
        };
        if vc <= 0.0 {
            return Profile {
                vc: 0.0,
                duration: 0.0,
            };
        }
        let duration = self.time(vc, &acc).0;
        Profile { vc, duration }
    }

    /// Bounds on [`fastest`](Self::fastest) that cost no root finding:
    /// the exact profile where a closed form needs no evaluation of the
    /// ramp distance (rest to rest, both ramps long); otherwise a lower
    /// bound on its duration (the same family without a jerk limit, which
    /// can only be faster) and a feasible slower profile (the long-ramp
    /// root: long ramps cover at least the distance of short ones, so it
    /// is a cruise speed at or below the optimal one). The planner solves
    /// exactly only for joints that may set a segment's duration.
    pub fn fastest_bounds(&self, lim: &JointLimits) -> Bounds {
        let (vm, a, j) = (lim.max_velocity, lim.max_acceleration, lim.jerk());
        let acc = Acc::new(a, j);
        // Only the closed forms that need no evaluation of `g` (the
        // long-ramp root is feasible in every case, `vm` or `max(v0, v1)`
        // included, so the others are left to `fastest`).
        let vlo = self.v0.max(self.v1).min(vm);
        let closed = if self.d <= 0.0 && vlo <= 0.0 {
            Ok(0.0)
        } else if self.v0 == 0.0 && self.v1 == 0.0 {
            Ok(rest_peak(self.d, lim))
        } else {
            self.fastest_long(a, j, vlo, vm)
        };
        match closed {
            Ok(vc) => {
                let upper = if vc <= 0.0 {
                    Profile {
                        vc: 0.0,
                        duration: 0.0,
                    }
                } else {
                    Profile {
                        vc,
                        duration: self.time(vc, &acc).0,
                    }
                };
                Bounds {
                    lower: upper.duration,
                    upper,
                    exact: true,
                }
            }
            Err(guess) => {
                let upper = Profile {
                    vc: guess,
                    duration: self.time(guess, &acc).0,
                };
                let (v0, v1) = (self.v0, self.v1);
                // Jerk-free: ramp distance (2 vc^2 - v0^2 - v1^2) / 2a.
                // At or above `guess >= max(v0, v1)` (both ramps speed up;
                // rounding aside it is so anyway), at most `vm`.
                let vt = ((2.0 * a * self.d + v0 * v0 + v1 * v1) * 0.5)
                    .sqrt()
                    .max(guess)
                    .min(vm);
                let ramps = (2.0 * vt * vt - v0 * v0 - v1 * v1) / (2.0 * a);
                let trap = (2.0 * vt - v0 - v1) / a + (self.d - ramps) / vt;
                // Margin for rounding: a bound too high could skip the
                // joint that sets the duration.
                let lower = (trap * (1.0 - 1e-9)).min(upper.duration);
                Bounds {
                    lower,
                    upper,
                    exact: false,
                }
            }
        }
    }

    /// The cruise speed of [`fastest`](Self::fastest) where it has a closed
    /// form (`Ok`, 0 for a joint that does not move), else `Err` with the
    /// long-ramp root clamped to `[max(v0, v1), vm]`.
    fn fastest_closed(&self, lim: &JointLimits, acc: &Acc) -> Result<f64, f64> {
        let (vm, a, j) = (lim.max_velocity, lim.max_acceleration, lim.jerk());
        let vlo = self.v0.max(self.v1).min(vm);
        if self.d <= 0.0 && vlo <= 0.0 {
            return Ok(0.0);
        }
        if self.g(vm, acc).1 <= self.d {
            Ok(vm)
        } else if self.v0 == 0.0 && self.v1 == 0.0 {
            Ok(rest_peak(self.d, lim))
        } else if self.g(vlo, acc).1 >= self.d {
            Ok(vlo)
        } else {
            self.fastest_long(a, j, vlo, vm)
        }
    }

    /// The root of `g(vc) = d` in `(vlo, vm)`, where `vlo = max(v0, v1) <
    /// vm`, `g(vlo) < d < g(vm)`, by Newton's method in `y = sqrt(vc -
    /// vlo)`. In `y` the ramp distance is convex and increasing: each leg's
    /// speed change is `y^2` plus a constant, its duration (`2 sqrt(dv / j)`
    /// or `dv / a + a / j`, joined with a continuous slope) is convex in
    /// `y`, and so is its product with the mean speed. Newton's iterates on
    /// a convex increasing function lie right of the root after the first
    /// step and then decrease monotonically to it, quadratically: no
    /// bracket, no bisection, a few steps. `guess` (the long-ramp root) lies
    /// left of the root, as long ramps cover at least the distance of short
    /// ones, so it yields a first step close to the root.
    fn fastest_root(&self, acc: &Acc, vlo: f64, vm: f64, guess: f64) -> f64 {
        // `G(y) = g(vlo + y^2) - d` and `dG/dy`, leg by leg: with
        // `dv = base + y^2`, `dist = (u + vc) / 2 * dur` and
        // `d dist / dy = y dur + (u + vc) / 2 * d dur / dy`.
        let f = |y: f64| {
            let vc = vlo + y * y;
            let mut g = -self.d;
            let mut dg = 0.0;
            for u in [self.v0, self.v1] {
                let dv = vc - u;
                let (dur, ddur) = if dv >= acc.regime {
                    (dv * acc.inv_a + acc.k, 2.0 * y * acc.inv_a)
                } else {
                    // `s = sqrt(dv j)`: duration `2 s / j`, its `y`
                    // derivative `2 y / s`, finite at `y -> 0` because `s
                    // >= y sqrt(j)`.
                    let s = (dv * acc.j).sqrt();
                    (2.0 * s * acc.inv_j, if s > 0.0 { 2.0 * y / s } else { 0.0 })
                };
                let mean = 0.5 * (u + vc);
                g += mean * dur;
                dg += y * dur + mean * ddur;
            }
            (g, dg)
        };
        let ym = (vm - vlo).sqrt();
        let y0 = (guess - vlo).max(0.0).sqrt();
        // First step from the left of the root (or the top of the range).
        let mut y = ym;
        if y0 > 0.0 {
            let (g, dg) = f(y0);
            if g >= 0.0 {
                y = y0;
            } else if dg > 0.0 {
                y = (y0 - g / dg).min(ym);
            }
        }
        for _ in 0..60 {
            let (g, dg) = f(y);
            // Rounding has reached the root (or crossed it): done.
            if g <= 0.0 || dg <= 0.0 {
                break;
            }
            let step = g / dg;
            y -= step;
            // Quadratic convergence: the error left is about the square
            // of this step, far below rounding.
            if step <= 1e-13 * y {
                break;
            }
        }
        vlo + y * y
    }

    /// The profile of duration exactly `t >= fastest.duration`, stretched by
    /// lowering the cruise speed. `fastest` is the time-optimal profile or
    /// any feasible one with a lower cruise speed (the upper bound of
    /// [`fastest_bounds`](Self::fastest_bounds)): the search only needs a
    /// cruise speed whose duration is at most `t`.
    pub fn stretched(&self, lim: &JointLimits, fastest: Profile, t: f64) -> Profile {
        if t <= fastest.duration * (1.0 + 1e-12) || fastest.vc <= 0.0 {
            return Profile {
                vc: fastest.vc,
                duration: t.max(fastest.duration),
            };
        }
        let (a, j) = (lim.max_acceleration, lim.jerk());
        let acc = Acc::new(a, j);
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
            let b = t - a / j;
            let disc = b * b - 4.0 * self.d / a;
            if disc >= 0.0 {
                // The smaller root, in the form without cancellation
                // (the product of the roots is a * d).
                let x = 2.0 * self.d / (b + disc.sqrt());
                if x * j >= a * a && x <= fastest.vc {
                    vc = Some(x);
                }
            }
        }
        // Every ramp reaching the acceleration limit (always so without a
        // jerk limit) makes the duration equation a quadratic: its root,
        // where the ramps are indeed long, is the answer. Elsewhere it is
        // still a close first guess (long-formula ramps are slower than
        // short ones, jerk-free ones faster: the answer lies between).
        let model = self
            .model_root(acc.inv_a, acc.k, t, fastest.vc)
            .or_else(|| self.model_root(acc.inv_a, 0.0, t, fastest.vc));
        if vc.is_none() {
            vc = model.filter(|&x| {
                (x - self.v0).abs() >= acc.regime
                    && (x - self.v1).abs() >= acc.regime
                    && self.d - self.g(x, &acc).1 >= -1e-12 * self.d
            });
        }
        let vc = match vc {
            Some(x) => x,
            None => {
                // Solve in u = 1 / vc: the duration is then nearly linear
                // (cruise time = distance * u), so Newton needs few steps.
                // f(u) = time(1 / u) - t is increasing, <= 0 at 1 / fastest.vc.
                let f = |u: f64| {
                    let (tt, dt) = self.time_of_inv(u, &acc);
                    (tt - t, dt)
                };
                let lo = 1.0 / fastest.vc;
                let guess = model.map_or(t / self.d, |vc| 1.0 / vc).max(lo);
                // No upper end known: the search finds one (f grows
                // without bound as u does, the cruise taking ever longer).
                1.0 / solve(f, lo, f64::INFINITY, guess, true)
            }
        };
        Profile { vc, duration: t }
    }

    /// Closed form of [`fastest`](Self::fastest) when both ramps reach the
    /// acceleration limit (always the case without a jerk limit): the ramp
    /// distance is then quadratic in `vc`,
    /// `g = vc^2 / a - (v0^2 + v1^2) / 2a + (v0 + v1 + 2 vc) a / 2j`.
    /// `Err` carries the root anyway (clamped), as a starting guess.
    fn fastest_long(&self, a: f64, j: f64, vlo: f64, vm: f64) -> Result<f64, f64> {
        let k = a / j;
        let c = -(self.v0 * self.v0 + self.v1 * self.v1) / (2.0 * a)
            + (self.v0 + self.v1) * k * 0.5
            - self.d;
        // vc^2 / a + k vc + c = 0, c < 0 here: one positive root.
        let disc = (k * k - 4.0 * c / a).max(0.0);
        let vc = 0.5 * a * (disc.sqrt() - k);
        let regime = a * k;
        if vc >= vlo && vc <= vm && vc - self.v0 >= regime && vc - self.v1 >= regime {
            Ok(vc)
        } else {
            Err(vc.clamp(vlo, vm))
        }
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

    /// The phases (duration, jerk) of the profile, for a positive direction.
    pub fn phases(&self, lim: &JointLimits, p: Profile, out: &mut Phases) {
        let (a, j) = (lim.max_acceleration, lim.jerk());
        let ra = Ramp::new((p.vc - self.v0).abs(), a, j);
        let rb = Ramp::new((p.vc - self.v1).abs(), a, j);
        let sa = if p.vc >= self.v0 { 1.0 } else { -1.0 };
        let sb = if self.v1 >= p.vc { 1.0 } else { -1.0 };
        out.push_ramp(&ra, sa, j);
        let cruise = (p.duration - ra.duration() - rb.duration()).max(0.0);
        out.push(cruise, 0.0, 0.0);
        out.push_ramp(&rb, sb, j);
    }
}

/// Safeguarded Newton iteration on a monotone function with a bracket:
/// `increasing` tells the sign convention (`f(lo) <= 0 <= f(hi)` when true,
/// the reverse otherwise). Falls back to bisection whenever a Newton step
/// leaves the bracket, so it always converges; `hi` may be infinite (then
/// an outgoing step doubles `x` until an upper end is found, `x > 0`).
/// Stops after a Newton step smaller than `1e-8` relative: convergence is
/// quadratic by then, so the step left is about its square, below the
/// rounding of the result.
fn solve(
    f: impl Fn(f64) -> (f64, f64),
    mut lo: f64,
    mut hi: f64,
    x0: f64,
    increasing: bool,
) -> f64 {
    let mut x = if hi.is_finite() {
        x0.clamp(lo, hi)
    } else {
        x0.max(lo)
    };
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
            nx = if hi.is_finite() {
                0.5 * (lo + hi)
            } else {
                2.0 * x
            };
        }
        let step = (nx - x).abs();
        if (newton && step <= 1e-8 * nx.abs())
            || step <= 1e-13 * nx.abs()
            || (hi.is_finite() && hi - lo <= 1e-13 * hi.abs())
        {
            return nx;
        }
        x = nx;
    }
    x
}

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
    pub fn new() -> Self {
        Phases {
            n: 0,
            dt: [0.0; 12],
            jerk: [0.0; 12],
            acc: [0.0; 12],
        }
    }

    pub fn push(&mut self, dt: f64, jerk: f64, acc: f64) {
        if dt > 0.0 && self.n < 12 {
            self.dt[self.n] = dt;
            self.jerk[self.n] = jerk;
            self.acc[self.n] = acc;
            self.n += 1;
        }
    }

    /// A ramp in direction `s` (+1 speeds up in the positive direction).
    fn push_ramp(&mut self, r: &Ramp, s: f64, j: f64) {
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
        out: &mut Vec<crate::piece::Piece>,
    ) -> (f64, f64, f64, f64) {
        let finite = lim.max_jerk.is_some();
        self.emit(t, x.position, x.velocity, x.acceleration, 1.0, finite, out)
    }

    /// Appends the pieces, starting at time `t` in state `(p, v, a)`, the
    /// whole profile mirrored by `dir` (+1 or -1). Returns the end time and
    /// state. With a finite jerk the acceleration is integrated (continuous);
    /// with an infinite one it is taken from `acc`.
    #[allow(clippy::too_many_arguments)] // a state (t, p, v, a) plus options
    pub fn emit(
        &self,
        mut t: f64,
        mut p: f64,
        mut v: f64,
        mut a: f64,
        dir: f64,
        finite_jerk: bool,
        out: &mut Vec<crate::piece::Piece>,
    ) -> (f64, f64, f64, f64) {
        for k in 0..self.n {
            let dt = self.dt[k];
            let jk = dir * self.jerk[k];
            if !finite_jerk {
                a = dir * self.acc[k];
            }
            out.push(crate::piece::Piece::jerk(t, dt, p, v, a, jk));
            p += dt * (v + dt * (0.5 * a + dt * jk / 6.0));
            v += dt * (a + 0.5 * dt * jk);
            a += dt * jk;
            t += dt;
        }
        if !finite_jerk {
            a = 0.0;
        }
        (t, p, v, a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lim(v: f64, a: f64, j: Option<f64>) -> JointLimits {
        JointLimits::new(v, a, j)
    }

    #[test]
    fn rest_peak_matches_definition() {
        let l = lim(2.0, 3.0, Some(10.0));
        for &d in &[0.01, 0.1, 0.5, 1.0, 3.0, 10.0] {
            let vc = rest_peak(d, &l);
            let r = Ramp::new(vc, 3.0, 10.0);
            let dist = vc * r.duration();
            assert!(vc <= 2.0 + 1e-12);
            assert!(
                vc == 2.0 || (dist - d).abs() < 1e-9 * d,
                "d={d} vc={vc} dist={dist}"
            );
        }
    }

    #[test]
    fn stretched_profile_has_requested_duration_and_distance() {
        let l = lim(2.0, 3.0, Some(10.0));
        let s = Segment1 {
            d: 1.3,
            v0: 0.4,
            v1: 0.2,
        };
        let f = s.fastest(&l);
        for k in [1.0, 1.01, 1.5, 3.0, 10.0] {
            let p = s.stretched(&l, f, f.duration * k);
            let mut ph = Phases::new();
            s.phases(&l, p, &mut ph);
            let mut out = Vec::new();
            let (t, x, v, a) = ph.emit(0.0, 0.0, 0.4, 0.0, 1.0, true, &mut out);
            assert!((t - f.duration * k).abs() < 1e-9, "k={k}");
            assert!((x - 1.3).abs() < 1e-9, "k={k} x={x}");
            assert!((v - 0.2).abs() < 1e-9 && a.abs() < 1e-9);
        }
    }
}
