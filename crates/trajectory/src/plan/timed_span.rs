//! A timed section: every keyframe on its time, in runs of one shape.
//! Shape-preserving runs refuse (or lengthen) segments too short even from
//! rest to rest; spline runs are checked against every limit after
//! planning, and stretched locally, then uniformly, when allowed.

use super::{Entry, OnLimit, Sections};
use crate::error::{PlanError, Quantity};
use crate::piece::Piece;
use crate::spline::{self, TimedShape};
use crate::timed;
use crate::JointLimits;

impl Sections<'_> {
    /// Plans the timed section from entry `i` over the consecutive timed
    /// entries after it; returns the entry it ends at.
    pub(super) fn timed(&mut self, i: usize) -> Result<usize, PlanError> {
        let entries = self.entries;
        let last = entries.len() - 1;
        let mut j = i + 1;
        while j < last && entries[j + 1].at.is_some() {
            j += 1;
        }
        let (mut b, mut dl) = (self.base, self.delay);
        self.times.clear();
        self.times.push(self.arrival[i]);
        for (k, e) in entries.iter().enumerate().take(j + 1).skip(i + 1) {
            let t = b + e.at.unwrap_or(0.0) + dl;
            let prev = self.times[self.times.len() - 1];
            if t <= prev {
                return Err(PlanError::TimeNotIncreasing {
                    keyframe: e.index,
                    at: e.at.unwrap_or(0.0),
                    previous: prev - b - dl,
                });
            }
            self.times.push(t);
            if entries[k].rebase {
                b = t;
                dl = 0.0;
            }
        }
        self.pos.clear();
        self.pos.extend(entries[i..=j].iter().map(|e| e.pos));
        let section = TimedSection {
            limits: self.limits,
            entries: &entries[i..=j],
            pos: &self.pos,
            on_limit: self.options.on_limit,
        };
        section.plan(&mut self.times, &mut self.out)?;
        self.arrival[i..=j].copy_from_slice(&self.times);
        Ok(j)
    }
}

/// Worst limit ratio of a timed segment over all joints, as a time factor:
/// velocity scales as 1/s, acceleration 1/s^2 and jerk 1/s^3 when the
/// segment's time is stretched by s. Also returns the first violation.
fn check_segment(
    limits: &[JointLimits],
    pieces: &[Vec<Piece>],
    t0: f64,
    t1: f64,
    keyframe: usize,
) -> (f64, Option<PlanError>) {
    let mut factor: f64 = 1.0;
    let mut first = None;
    let tol = 1.0 + 1e-9;
    for (j, (ps, lim)) in pieces.iter().zip(limits).enumerate() {
        // A joint's pieces follow each other in time: find the segment's
        // by bisection rather than scanning them all (a run of n segments
        // is then checked in n log n, not n^2).
        let mid = |p: &Piece| 0.5 * (p.t0 + p.t1);
        let start = ps.partition_point(|p| mid(p) <= t0);
        for p in ps[start..].iter().take_while(|p| mid(p) < t1) {
            let (lo, hi) = p.range(0);
            let checks = [
                (Quantity::Velocity, p.peak(1), lim.max_velocity, 1.0),
                (Quantity::Acceleration, p.peak(2), lim.max_acceleration, 2.0),
                (Quantity::Jerk, p.peak(3), lim.jerk(), 3.0),
            ];
            for (q, peak, limit, power) in checks {
                if peak > limit * tol {
                    factor = factor.max((peak / limit).powf(1.0 / power));
                    first.get_or_insert(PlanError::LimitExceeded {
                        keyframe,
                        joint: j,
                        quantity: q,
                        peak,
                        limit,
                    });
                }
            }
            let slack = 1e-9 * (1.0 + lim.max_position.abs().max(lim.min_position.abs()).min(1e12));
            let below = (lo < lim.min_position - slack).then_some((lo, lim.min_position));
            let above = (hi > lim.max_position + slack).then_some((hi, lim.max_position));
            if let Some((peak, limit)) = below.or(above) {
                // Position violations cannot be stretched away: report
                // them at once, with no factor.
                return (
                    f64::INFINITY,
                    Some(PlanError::LimitExceeded {
                        keyframe,
                        joint: j,
                        quantity: Quantity::Position,
                        peak,
                        limit,
                    }),
                );
            }
        }
    }
    (factor, first)
}

/// Local stretching rounds before the uniform stretch.
const LOCAL_ATTEMPTS: usize = 12;

/// One timed section `entries[0..=m]` and what planning it needs; its
/// times are passed apart, as they change when a run is stretched.
struct TimedSection<'s, 'e> {
    limits: &'s [JointLimits],
    entries: &'s [Entry<'e>],
    pos: &'s [&'e [f64]],
    on_limit: OnLimit,
}

impl TimedSection<'_, '_> {
    /// Plans the section at `times` (updated in place when stretched),
    /// split into runs of equal shape, appending to `out`.
    fn plan(&self, times: &mut [f64], out: &mut [Vec<Piece>]) -> Result<(), PlanError> {
        let m = self.entries.len() - 1;
        let mut a = 0;
        let mut buf: Vec<Vec<Piece>> = vec![Vec::new(); self.limits.len()];
        while a < m {
            let shape = self.entries[a + 1].shape;
            let mut b = a + 1;
            while b < m && self.entries[b + 1].shape == shape {
                b += 1;
            }
            if shape == TimedShape::ShapePreserving {
                self.preserving_run(a, b, times, &mut buf)?;
            } else {
                self.spline_run(a, b, shape, times, &mut buf)?;
            }
            for (o, p) in out.iter_mut().zip(&mut buf) {
                o.append(p);
            }
            a = b;
        }
        Ok(())
    }

    /// A spline run `a..=b` in `shape`, its times lengthened (with
    /// [`OnLimit::Stretch`]) until every segment is within the limits.
    fn spline_run(
        &self,
        a: usize,
        b: usize,
        shape: TimedShape,
        times: &mut [f64],
        buf: &mut [Vec<Piece>],
    ) -> Result<(), PlanError> {
        // Stretching loop: local stretching of offending segments first
        // (keeps the others on time), then one uniform stretch, which is
        // exact because a uniformly stretched run has the same shape (its
        // peaks scale by 1/s, 1/s^2, 1/s^3).
        let mut factors = vec![1.0f64; b - a];
        let mut attempt = 0;
        loop {
            buf.iter_mut().for_each(Vec::clear);
            spline::run(shape, &times[a..=b], &self.pos[a..=b], buf);
            let mut worst: f64 = 1.0;
            let mut first_err = None;
            for k in a..b {
                let (f, e) = check_segment(
                    self.limits,
                    buf,
                    times[k],
                    times[k + 1],
                    self.entries[k + 1].index,
                );
                if let (Some(e), true) = (e, first_err.is_none() || f.is_infinite()) {
                    if f.is_infinite() {
                        return Err(e);
                    }
                    first_err = Some(e);
                }
                factors[k - a] = f;
                worst = worst.max(f);
            }
            let Some(err) = first_err else { break };
            if self.on_limit == OnLimit::Error || attempt > LOCAL_ATTEMPTS + 1 {
                return Err(err);
            }
            let uniform = attempt >= LOCAL_ATTEMPTS;
            attempt += 1;
            let mut shift = 0.0;
            let mut prev_old = times[a];
            for k in a..b {
                let h = times[k + 1] - prev_old;
                prev_old = times[k + 1];
                let f = if uniform { worst } else { factors[k - a] };
                let f = if f > 1.0 { f * (1.0 + 1e-6) } else { 1.0 };
                shift += h * (f - 1.0);
                times[k + 1] += shift;
            }
            // Everything after the run moves by the same amount.
            for t in &mut times[b + 1..] {
                *t += shift;
            }
        }
        Ok(())
    }

    /// A shape-preserving run `a..=b`: every segment too short even for a
    /// rest-to-rest move is refused, or with [`OnLimit::Stretch`]
    /// lengthened to the shortest such move (every later keyframe delayed
    /// by as much); the others keep their times exactly.
    fn preserving_run(
        &self,
        a: usize,
        b: usize,
        times: &mut [f64],
        buf: &mut [Vec<Piece>],
    ) -> Result<(), PlanError> {
        buf.iter_mut().for_each(Vec::clear);
        // One pass: lengthening segment `k` delays every later keyframe alike,
        // which leaves the later segments' durations as they were, so each
        // segment is checked once. `shift` is the delay carried so far.
        let mut shift = 0.0;
        for k in a..b {
            times[k + 1] += shift;
            let needed = timed::rest_to_rest(self.limits, self.pos, k);
            let available = times[k + 1] - times[k];
            if needed <= available * (1.0 + 1e-9) {
                continue;
            }
            if self.on_limit == OnLimit::Error {
                return Err(PlanError::TooSoon {
                    keyframe: self.entries[k + 1].index,
                    needed,
                    available,
                });
            }
            let extra = needed * (1.0 + 1e-9) - available;
            times[k + 1] += extra;
            shift += extra;
        }
        for t in &mut times[b + 1..] {
            *t += shift;
        }
        timed::run(self.limits, &times[a..=b], &self.pos[a..=b], buf);
        Ok(())
    }
}
