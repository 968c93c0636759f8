//! The time-optimal profile of a segment: closed forms where they exist,
//! bounds that need no root finding, and a Newton search for the rest.

use super::ramp::{cube_root_rough, rest_peak, rest_short, Acc};
use super::{Bounds, Profile, Segment1};

impl Segment1 {
    /// The time-optimal profile. Precondition: the ramps alone fit, i.e.
    /// `g(max(v0, v1)) <= d` (the planner caps via speeds to ensure it).
    pub fn fastest(&self, acc: &Acc) -> Profile {
        if let Some(p) = self.short_rest(acc) {
            return p;
        }
        let vm = acc.vm;
        let vc = match self.fastest_closed(acc) {
            Ok(vc) => vc,
            // The long-ramp root (outside its regime) is a good start.
            Err(guess) => self.fastest_root(acc, self.v0.max(self.v1).min(vm), vm, guess),
        };
        if vc <= 0.0 {
            return Profile {
                vc: 0.0,
                duration: 0.0,
            };
        }
        let duration = self.time(vc, acc).0;
        Profile { vc, duration }
    }

    /// Bounds on [`fastest`](Self::fastest) that cost no root finding:
    /// [`fastest_upper`](Self::fastest_upper) and, where that is not
    /// exact, a lower bound on the duration (the same family without a
    /// jerk limit, which can only be faster).
    pub fn fastest_bounds(&self, acc: &Acc) -> Bounds {
        let (upper, exact) = self.fastest_upper(acc);
        if exact {
            return Bounds {
                lower: upper.duration,
                upper,
                exact,
            };
        }
        let (vm, a, guess) = (acc.vm, acc.a, upper.vc);
        let (v0, v1) = (self.v0, self.v1);
        // Jerk-free: ramp distance (2 vc^2 - v0^2 - v1^2) / 2a.
        // At or above `guess >= max(v0, v1)` (both ramps speed up;
        // rounding aside it is so anyway), at most `vm`.
        let vt = ((2.0 * a * self.d + v0 * v0 + v1 * v1) * 0.5)
            .sqrt()
            .max(guess)
            .min(vm);
        let ramps = (2.0 * vt * vt - v0 * v0 - v1 * v1) * (0.5 * acc.inv_a);
        let trap = (2.0 * vt - v0 - v1) * acc.inv_a + (self.d - ramps) / vt;
        // Margin for rounding: a bound too high could skip the
        // joint that sets the duration.
        let lower = (trap * (1.0 - 1e-9)).min(upper.duration);
        Bounds {
            lower,
            upper,
            exact,
        }
    }

    /// A feasible profile at least as long as the time-optimal one, and
    /// whether it is the time-optimal one, at no root finding: the exact
    /// profile where a closed form needs no evaluation of the ramp
    /// distance (rest to rest, both ramps long), otherwise the long-ramp
    /// root (long ramps cover at least the distance of short ones, so it
    /// is a cruise speed at or below the optimal one). The planner solves
    /// exactly only for joints that may set a segment's duration.
    #[inline]
    pub fn fastest_upper(&self, acc: &Acc) -> (Profile, bool) {
        if let Some(upper) = self.short_rest(acc) {
            return (upper, true);
        }
        let vm = acc.vm;
        // Only the closed forms that need no evaluation of `g` (the
        // long-ramp root is feasible in every case, `vm` or `max(v0, v1)`
        // included, so the others are left to `fastest`).
        let vlo = self.v0.max(self.v1).min(vm);
        let closed = if self.d <= 0.0 && vlo <= 0.0 {
            Ok(0.0)
        } else if self.v0 == 0.0 && self.v1 == 0.0 {
            Ok(rest_peak(self.d, acc))
        } else {
            self.fastest_long(acc, vlo, vm)
        };
        match closed {
            Ok(vc) if vc <= 0.0 => (
                Profile {
                    vc: 0.0,
                    duration: 0.0,
                },
                true,
            ),
            Ok(vc) => (
                Profile {
                    vc,
                    duration: self.time(vc, acc).0,
                },
                true,
            ),
            Err(guess) => (
                Profile {
                    vc: guess,
                    duration: self.time(guess, acc).0,
                },
                false,
            ),
        }
    }

    /// The time-optimal profile of a short rest-to-rest segment (see
    /// [`rest_short`]), if this is one.
    #[inline]
    pub(super) fn short_rest(&self, acc: &Acc) -> Option<Profile> {
        if self.v0 != 0.0 || self.v1 != 0.0 {
            return None;
        }
        rest_short(self.d, acc).map(|(vc, duration)| Profile { vc, duration })
    }

    /// The cruise speed of [`fastest`](Self::fastest) where it has a closed
    /// form (`Ok`, 0 for a joint that does not move), else `Err` with the
    /// long-ramp root clamped to `[max(v0, v1), vm]`.
    fn fastest_closed(&self, acc: &Acc) -> Result<f64, f64> {
        let vm = acc.vm;
        let vlo = self.v0.max(self.v1).min(vm);
        if self.d <= 0.0 && vlo <= 0.0 {
            return Ok(0.0);
        }
        if self.v0 == 0.0 && self.v1 == 0.0 {
            // Rest to rest (`vm` included): no ramp distance to evaluate.
            Ok(rest_peak(self.d, acc))
        } else if self.g(vm, acc).1 <= self.d {
            Ok(vm)
        } else if self.g(vlo, acc).1 >= self.d {
            Ok(vlo)
        } else {
            self.fastest_long(acc, vlo, vm)
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
        // Where every ramp is short (below `regime`), the speeds at the
        // ends small beside the cruise speed, the rest-to-rest root of
        // pure jerk ramps, `2 vc sqrt(vc / j) = d`, is within a few percent
        // of the root, much closer than the long-ramp one: start there
        // (from either side: convexity takes a step from the left to the
        // right of the root).
        let pure = cube_root_rough(0.25 * self.d * self.d * acc.j);
        let guess = if pure > vlo && pure < vm.min(acc.regime) {
            pure
        } else {
            guess
        };
        let y0 = (guess - vlo).max(0.0).sqrt();
        // First step from the guess (or the top of the range).
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
            // of this step over `y`, some 1e-12 of `y` once the step is
            // 1e-6 of it (an evaluation fewer than waiting for rounding,
            // and far below any distance that matters).
            if step <= 1e-6 * y {
                break;
            }
        }
        vlo + y * y
    }

    /// Closed form of [`fastest`](Self::fastest) when both ramps reach the
    /// acceleration limit (always the case without a jerk limit): the ramp
    /// distance is then quadratic in `vc`,
    /// `g = vc^2 / a - (v0^2 + v1^2) / 2a + (v0 + v1 + 2 vc) a / 2j`.
    /// `Err` carries the root anyway (clamped), as a starting guess.
    #[inline]
    fn fastest_long(&self, acc: &Acc, vlo: f64, vm: f64) -> Result<f64, f64> {
        let (a, inv_a, k, regime) = (acc.a, acc.inv_a, acc.k, acc.regime);
        let c = -(self.v0 * self.v0 + self.v1 * self.v1) * (0.5 * inv_a)
            + (self.v0 + self.v1) * k * 0.5
            - self.d;
        // vc^2 / a + k vc + c = 0, c < 0 here: one positive root.
        let disc = (k * k - 4.0 * c * inv_a).max(0.0);
        let vc = 0.5 * a * (disc.sqrt() - k);
        if vc >= vlo && vc <= vm && vc - self.v0 >= regime && vc - self.v1 >= regime {
            Ok(vc)
        } else {
            Err(vc.clamp(vlo, vm))
        }
    }
}
