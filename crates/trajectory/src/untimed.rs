//! Untimed keyframes: as fast as the limits allow, through the
//! intermediate keyframes without stopping where the motion continues.
//!
//! Method (blended double-S segments):
//!
//! 1. Each joint gets a speed at each intermediate keyframe: zero where the
//!    joint turns back or pauses there (so it never overshoots), otherwise
//!    the largest speed, up to `max_velocity`, from which it could still
//!    stop within a quarter of either neighbouring distance. That cap
//!    guarantees every segment profile exists for any duration (see
//!    `profile`), acceleration is zero at every keyframe, so velocity and
//!    acceleration are continuous there.
//! 2. Each segment takes the longest of the joints' time-optimal durations;
//!    every other joint's profile is stretched to that duration by lowering
//!    its cruise speed, so all joints reach every keyframe together.
//! 3. Speeds at keyframes are then lowered where a stretched joint would
//!    otherwise dip and rise again (to twice its average speed on either
//!    side), wherever that keeps both neighbouring segments within their
//!    durations. Every step only ever builds profiles inside the limits.

use crate::piece::Piece;
use crate::profile::{rest_peak, Acc, Phases, Profile, Segment1};
use crate::JointLimits;

/// Reused buffers of the untimed planner.
#[derive(Debug, Default)]
pub(crate) struct Scratch {
    /// Signed speed per keyframe and joint, `k * joints + j`.
    via: Vec<f64>,
    /// Fastest profile per segment and joint.
    fastest: Vec<Profile>,
    /// Duration per segment.
    pub durations: Vec<f64>,
    /// Per joint of the current segment: `fastest` holds the time-optimal
    /// profile, not only a bound.
    exact: Vec<bool>,
    /// Each joint's bounds, with their reciprocals made once.
    rates: Vec<Acc>,
}

/// Plans an untimed section through `pos[0..=n]` starting at `t0` at rest.
/// Appends pieces to `out[j]`; segment durations are left in
/// `scratch.durations`. With `stop` every keyframe is a stop (the
/// comparison baseline).
pub(crate) fn section(
    limits: &[JointLimits],
    pos: &[&[f64]],
    t0: f64,
    stop: bool,
    scratch: &mut Scratch,
    out: &mut [Vec<Piece>],
) {
    let n = pos.len() - 1;
    scratch.reset(limits, n);
    if !stop {
        scratch.keyframe_speeds(pos);
    }
    scratch.segment_durations(pos);
    if !stop && n > 1 {
        scratch.smooth_dips(pos);
    }
    scratch.emit(pos, t0, out);
}

impl Scratch {
    /// Sizes the buffers for `n` segments of `limits.len()` joints, all at rest.
    fn reset(&mut self, limits: &[JointLimits], n: usize) {
        let nj = limits.len();
        self.rates.clear();
        self.rates.extend(limits.iter().map(Acc::of));
        self.via.clear();
        self.via.resize((n + 1) * nj, 0.0);
        self.fastest.clear();
        self.fastest.resize(
            n * nj,
            Profile {
                vc: 0.0,
                duration: 0.0,
            },
        );
        self.durations.clear();
        self.durations.resize(n, 0.0);
    }

    /// Step 1: the capped speed of every joint at every intermediate keyframe.
    fn keyframe_speeds(&mut self, pos: &[&[f64]]) {
        let nj = self.rates.len();
        let n = pos.len() - 1;
        for k in 1..n {
            for (j, lim) in self.rates.iter().enumerate() {
                let (dp, dn) = (pos[k][j] - pos[k - 1][j], pos[k + 1][j] - pos[k][j]);
                if dp * dn > 0.0 {
                    // `rest_peak` increases with the distance: the smaller
                    // neighbour sets the cap (one evaluation, same value).
                    let cap = rest_peak(0.5 * dp.abs().min(dn.abs()), lim);
                    self.via[k * nj + j] = dp.signum() * cap.min(lim.vm);
                }
            }
        }
    }

    /// Step 2: each segment's duration, the slowest joint's time-optimal one.
    fn segment_durations(&mut self, pos: &[&[f64]]) {
        let Scratch {
            via,
            fastest,
            durations,
            exact,
            rates,
        } = self;
        let nj = rates.len();
        exact.clear();
        exact.resize(nj, false);
        for (k, duration) in durations.iter_mut().enumerate() {
            // Only the slowest joint's time-optimal duration matters, and the
            // stretched profiles only need a feasible profile no faster than
            // the time-optimal one. Every joint's bound first (the exact
            // profile for some), then, largest first, an exact solve of every
            // bound above the longest exact duration so far: a joint left out
            // has a time-optimal duration at most its bound, at most that
            // duration, so `t` is exact.
            let s = |j: usize| {
                Segment1::between(
                    pos[k + 1][j] - pos[k][j],
                    via[k * nj + j],
                    via[(k + 1) * nj + j],
                )
            };
            let row = &mut fastest[k * nj..(k + 1) * nj];
            let mut t: f64 = 0.0;
            for (j, lim) in rates.iter().enumerate() {
                let (upper, ex) = s(j).fastest_upper(lim);
                row[j] = upper;
                exact[j] = ex;
                if ex {
                    t = t.max(upper.duration);
                }
            }
            loop {
                let mut pick = None;
                let mut top = t;
                for (j, f) in row.iter().enumerate() {
                    if !exact[j] && f.duration > top {
                        top = f.duration;
                        pick = Some(j);
                    }
                }
                let Some(j) = pick else { break };
                row[j] = s(j).fastest(&rates[j]);
                exact[j] = true;
                t = t.max(row[j].duration);
            }
            *duration = t;
        }
    }

    /// Step 3: lowers keyframe speeds where a joint would dip and rise again.
    fn smooth_dips(&mut self, pos: &[&[f64]]) {
        // A joint much faster than the segment's pace would brake and
        // accelerate again inside the segment; give it a speed in line with
        // the pace instead, where that does not lengthen either neighbouring
        // segment (so the durations stay as they are).
        let Scratch {
            via,
            fastest,
            durations,
            rates,
            ..
        } = self;
        let nj = rates.len();
        let n = pos.len() - 1;
        for k in 1..n {
            for (j, lim) in rates.iter().enumerate() {
                let v = via[k * nj + j];
                if v == 0.0 {
                    continue;
                }
                let (dp, dn) = (pos[k][j] - pos[k - 1][j], pos[k + 1][j] - pos[k][j]);
                let pace = 2.0 * (dp.abs() / durations[k - 1]).min(dn.abs() / durations[k]);
                // Only worth it for a marked dip.
                if pace >= 0.8 * v.abs() {
                    continue;
                }
                let vp = v.signum() * pace;
                let Some(before) =
                    Segment1::between(dp, via[(k - 1) * nj + j], vp).fits(lim, durations[k - 1])
                else {
                    continue;
                };
                if let Some(after) =
                    Segment1::between(dn, vp, via[(k + 1) * nj + j]).fits(lim, durations[k])
                {
                    via[k * nj + j] = vp;
                    fastest[(k - 1) * nj + j] = before;
                    fastest[k * nj + j] = after;
                }
            }
        }
    }

    /// Step 4: appends each joint's stretched segment profiles to `out[j]`.
    fn emit(&self, pos: &[&[f64]], t0: f64, out: &mut [Vec<Piece>]) {
        let nj = self.rates.len();
        let n = pos.len() - 1;
        let (via, durations) = (&self.via, &self.durations);
        let mut phases = Phases::new();
        for (j, lim) in self.rates.iter().enumerate() {
            let finite = lim.finite;
            let mut t = t0;
            for k in 0..n {
                let d = pos[k + 1][j] - pos[k][j];
                let (vin, vout) = (via[k * nj + j], via[(k + 1) * nj + j]);
                let s = Segment1::between(d, vin, vout);
                let p = s.stretched(lim, self.fastest[k * nj + j], durations[k]);
                phases.n = 0;
                if s.d == 0.0 && s.v0 == 0.0 && s.v1 == 0.0 {
                    out[j].push(Piece::hold(t, t + durations[k], pos[k][j]));
                } else {
                    s.phases(lim, p, &mut phases);
                    let dir = if d >= 0.0 { 1.0 } else { -1.0 };
                    phases.emit(t, pos[k][j], vin, 0.0, dir, finite, &mut out[j]);
                }
                t += durations[k];
            }
        }
    }
}
