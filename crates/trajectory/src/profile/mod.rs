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
//!
//! Parts: `ramp` (one speed change, and the rest-to-rest peak speed),
//! `fastest` (the time-optimal profile and its cheap bounds), `stretch` (a
//! longer duration by a lower cruise speed) and `phases` (the result as
//! constant-jerk phases and polynomial pieces).

mod fastest;
mod phases;
mod ramp;
mod stretch;

pub(crate) use phases::{Phases, SIXTH};
use ramp::leg;
pub(crate) use ramp::rest_peak;
pub(crate) use ramp::{Acc, Ramp};

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

impl Segment1 {
    /// The segment covering `d` (either sign) from speed `vin` to `vout`,
    /// normalised to a positive direction. The planners give a keyframe
    /// either no speed or one in the direction of motion, so the speeds
    /// become non-negative.
    #[inline]
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
    pub fn fits(&self, lim: &Acc, limit: f64) -> Option<Profile> {
        let b = self.fastest_bounds(lim);
        if b.upper.duration <= limit {
            Some(b.upper)
        } else if b.exact || b.lower > limit {
            None
        } else {
            Some(self.fastest(lim)).filter(|f| f.duration <= limit)
        }
    }

    /// Whether a profile cruising at `vc` (at least `max(v0, v1)`, within
    /// the speed limit) fits the distance: its ramps cover no more than
    /// `d`. The ramp distance grows with `vc`, so this is whether the
    /// time-optimal cruise speed is at least `vc`, known without solving
    /// for it.
    #[inline]
    pub fn cruises_at(&self, lim: &Acc, vc: f64) -> bool {
        self.g(vc, lim).1 <= self.d
    }

    /// Total ramp distance and its derivative at cruise speed `vc`.
    #[inline(always)]
    fn g(&self, vc: f64, c: &Acc) -> (f64, f64, f64, f64) {
        let (ta, da, dta, dda) = leg(self.v0, vc, c);
        if self.v1 == self.v0 {
            // Rest to rest, mostly: the two ramps alike.
            return (2.0 * ta, 2.0 * da, 2.0 * dta, 2.0 * dda);
        }
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

    /// The phases (duration, jerk) of the profile, for a positive direction.
    #[inline]
    pub fn phases(&self, acc: &Acc, p: Profile, out: &mut Phases) {
        let ra = Ramp::of((p.vc - self.v0).abs(), acc);
        // Rest to rest, mostly: the two ramps alike (one square root).
        let rb = if self.v1 == self.v0 {
            ra
        } else {
            Ramp::of((p.vc - self.v1).abs(), acc)
        };
        self.push_phases(acc.j, p, &ra, &rb, out);
    }

    /// The phases of the time-optimal profile: [`phases`](Self::phases) of
    /// [`fastest`](Self::fastest), a short rest-to-rest profile's made
    /// straight from its jerk phase (no square root: the follower's usual
    /// case).
    #[inline]
    pub fn fastest_phases(&self, acc: &Acc, out: &mut Phases) {
        match self.short_rest(acc) {
            Some(p) => {
                // Its ramps are two jerk phases of a quarter of its duration.
                let tj = 0.25 * p.duration;
                let r = Ramp {
                    tj,
                    ta: 0.0,
                    peak: acc.j * tj,
                };
                self.push_phases(acc.j, p, &r, &r, out);
            }
            None => self.phases(acc, self.fastest(acc), out),
        }
    }

    /// Pushes the profile `p` whose ramps are `ra` and `rb` (jerk `j`).
    #[inline(always)]
    fn push_phases(&self, j: f64, p: Profile, ra: &Ramp, rb: &Ramp, out: &mut Phases) {
        let sa = if p.vc >= self.v0 { 1.0 } else { -1.0 };
        let sb = if self.v1 >= p.vc { 1.0 } else { -1.0 };
        out.push_ramp(ra, sa, j);
        let cruise = (p.duration - ra.duration() - rb.duration()).max(0.0);
        out.push(cruise, 0.0, 0.0);
        out.push_ramp(rb, sb, j);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A short rest-to-rest move in closed form: with `j = 10` and jerk
    /// phases of 0.1 s each ramp covers `j tj^3 = 0.01`, so `d = 0.02`
    /// peaks at `j tj^2 = 0.1` and lasts 0.4 s, well inside `a = 3` (a
    /// ramp peaks at `j tj = 1`) and `v = 2`.
    #[test]
    fn a_short_rest_to_rest_move_is_four_jerk_phases() {
        let l = Acc::of(&crate::JointLimits::new(2.0, 3.0, Some(10.0)));
        let s = Segment1 {
            d: 0.02,
            v0: 0.0,
            v1: 0.0,
        };
        let p = s.fastest(&l);
        assert!(
            (p.vc - 0.1).abs() < 1e-12 && (p.duration - 0.4).abs() < 1e-12,
            "{p:?}"
        );
        let mut ph = Phases::new();
        s.fastest_phases(&l, &mut ph);
        assert_eq!(ph.n, 4);
        for (k, jerk) in [10.0, -10.0, -10.0, 10.0].into_iter().enumerate() {
            assert!((ph.dt[k] - 0.1).abs() < 1e-12 && ph.jerk[k] == jerk, "{k}");
        }
        // The same as the phases of the fastest profile, square root and
        // all.
        let mut slow = Phases::new();
        s.phases(&l, p, &mut slow);
        assert_eq!(slow.n, 4);
        for k in 0..4 {
            assert!((slow.dt[k] - ph.dt[k]).abs() < 1e-12 && slow.jerk[k] == ph.jerk[k]);
        }
    }

    #[test]
    fn stretched_profile_has_requested_duration_and_distance() {
        let l = Acc::of(&crate::JointLimits::new(2.0, 3.0, Some(10.0)));
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
