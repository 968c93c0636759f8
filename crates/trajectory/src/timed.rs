//! Timed keyframes, shape-preserving: the default interpolation.
//!
//! Each joint is planned on its own (the times are given, so joints need
//! not wait for each other), segment by segment, with the same jerk-limited
//! profiles as untimed motion (`profile`): a velocity that never changes
//! sign inside a segment, zero acceleration at every keyframe, and a
//! duration met exactly by lowering the cruise speed. Hence:
//!
//! - a joint never leaves the range of the two keyframes around a segment;
//! - where it turns back (or pauses) at a keyframe its speed there is zero;
//! - velocity and acceleration are continuous, jerk within its limit;
//! - every segment that a rest-to-rest move can do in its time is planned
//!   in exactly that time, so a motion feasible by stopping at every
//!   keyframe is never refused.
//!
//! Where a joint carries on through a keyframe it keeps moving at a speed
//! in line with both neighbouring segments (the harmonic mean of their
//! average speeds, which is at most twice the smaller one), capped so that
//! the joint could still stop within half of either neighbouring distance.
//! A speed that leaves a neighbouring segment infeasible in its time is
//! halved, and after a few halvings set to zero: zero is always feasible,
//! so the search ends.

use crate::piece::Piece;
use crate::profile::{rest_peak, Acc, Phases, Profile, Segment1};
use crate::JointLimits;

/// Halvings of a via speed before it is set to zero.
const HALVINGS: u32 = 3;

/// The shortest rest-to-rest time of each segment over every joint.
pub(crate) fn rest_to_rest(limits: &[JointLimits], pos: &[&[f64]], k: usize) -> f64 {
    limits
        .iter()
        .enumerate()
        .map(|(j, lim)| {
            let d = (pos[k + 1][j] - pos[k][j]).abs();
            if d == 0.0 {
                return 0.0;
            }
            Segment1 {
                d,
                v0: 0.0,
                v1: 0.0,
            }
            .fastest(&Acc::of(lim))
            .duration
        })
        .fold(0.0, f64::max)
}

/// A feasible profile of `s` within `h` (for [`Segment1::stretched`]), or
/// `None` when the time-optimal one is longer. A segment that does not move
/// fits only at rest at both ends.
fn fit(s: Segment1, lim: &Acc, h: f64) -> Option<Profile> {
    if s.d == 0.0 {
        return (s.v0 == 0.0 && s.v1 == 0.0).then_some(Profile {
            vc: 0.0,
            duration: 0.0,
        });
    }
    s.fits(lim, h)
}

/// Plans one run `times[0..=m]`, `pos[k][j]`, at rest at both ends, and
/// appends the pieces to `out[j]`. Precondition: no segment is shorter than
/// its [`rest_to_rest`] time.
pub(crate) fn run(limits: &[JointLimits], times: &[f64], pos: &[&[f64]], out: &mut [Vec<Piece>]) {
    let m = times.len() - 1;
    let mut via = vec![0.0; m + 1];
    let mut cuts = vec![0u32; m + 1];
    let mut fits: Vec<Option<Profile>> = vec![None; m];
    let mut phases = Phases::new();
    for (j, lim) in limits.iter().enumerate() {
        let lim = &Acc::of(lim);
        let d = |k: usize| pos[k + 1][j] - pos[k][j];
        let h = |k: usize| times[k + 1] - times[k];
        via.fill(0.0);
        cuts.fill(0);
        for (k, v) in via.iter_mut().enumerate().take(m).skip(1) {
            let (dp, dn) = (d(k - 1), d(k));
            if dp * dn > 0.0 {
                let (a, b) = ((dp / h(k - 1)).abs(), (dn / h(k)).abs());
                let pace = 2.0 * a * b / (a + b);
                let cap = rest_peak(0.5 * dp.abs().min(dn.abs()), lim).min(lim.vm);
                *v = dp.signum() * pace.min(cap);
            }
        }
        // Lower the speeds at the ends of infeasible segments until every
        // segment fits (each pass only lowers speeds; all zero fits). The
        // last pass changes nothing, so it leaves each segment's profile
        // for its final speeds in `fits`.
        let mut changed = true;
        while changed {
            changed = false;
            for k in 0..m {
                fits[k] = fit(Segment1::between(d(k), via[k], via[k + 1]), lim, h(k));
                if fits[k].is_some() {
                    continue;
                }
                for e in [k, k + 1] {
                    if via[e] != 0.0 {
                        cuts[e] += 1;
                        via[e] = if cuts[e] > HALVINGS {
                            0.0
                        } else {
                            0.5 * via[e]
                        };
                        changed = true;
                    }
                }
            }
        }
        for k in 0..m {
            let (vin, vout) = (via[k], via[k + 1]);
            let s = Segment1::between(d(k), vin, vout);
            if s.d == 0.0 {
                out[j].push(Piece::hold(times[k], times[k + 1], pos[k][j]));
                continue;
            }
            // Every segment fits after the last pass; solving is only a
            // fallback should that ever not hold.
            let fastest = fits[k].unwrap_or_else(|| s.fastest(lim));
            let p = s.stretched(lim, fastest, h(k));
            phases.n = 0;
            s.phases(lim, p, &mut phases);
            let dir = if d(k) >= 0.0 { 1.0 } else { -1.0 };
            phases.emit(times[k], pos[k][j], vin, 0.0, dir, lim.finite, &mut out[j]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_through_without_stopping_where_the_motion_continues() {
        let lim = [JointLimits::new(2.0, 10.0, Some(100.0))];
        let times = [0.0, 1.0, 2.0, 3.0];
        let pos: [&[f64]; 4] = [&[0.0], &[0.5], &[1.0], &[0.2]];
        let mut out = vec![Vec::new()];
        run(&lim, &times, &pos, &mut out);
        let at = |t: f64| {
            out[0]
                .iter()
                .find(|p| p.t0 <= t && t <= p.t1)
                .map(|p| p.eval(t))
                .unwrap_or((f64::NAN, f64::NAN, f64::NAN))
        };
        // Continues through keyframe 1 (0.5 per s on both sides).
        assert!((at(1.0).1 - 0.5).abs() < 1e-6, "{:?}", at(1.0));
        // Turns back at keyframe 2: at rest there.
        assert!(at(2.0).1.abs() < 1e-9);
        for (k, &t) in times.iter().enumerate() {
            assert!((at(t).0 - pos[k][0]).abs() < 1e-9, "keyframe {k}");
        }
    }
}
