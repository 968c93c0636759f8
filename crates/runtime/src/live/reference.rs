//! One joint's reference while following live targets: a piecewise-linear
//! path through the targets received, each reached one target interval
//! after it was taken, and through a chunk's points at their own times.
//!
//! The reference never leaves the range of the points it passes through
//! (a linear piece lies between its two ends), so it stays inside the
//! envelope of the targets received: nothing is extrapolated past the
//! newest target. Once the last point is reached it holds there.

use std::collections::VecDeque;

use servobus_trajectory::{Goal, JointLimits, TARGET_SPEED_SHARE};

/// Stamp differences outside this range are no target interval, s.
pub(super) const INTERVAL: (f64, f64) = (0.001, 0.5);

/// Pieces shorter than this are taken as straight, s.
const MIN_PIECE: f64 = 1e-3;

/// How long the follower takes a bend of the reference to last when it
/// keeps to its speed limit, s: about the longest a follower's plan to its
/// goal takes at the joints' limits.
const BEND_HORIZON: f64 = 0.25;

/// How many recent target lateness figures the delay and the schedule
/// are taken from.
const INTERVALS: usize = 8;

/// How many recent target intervals the stream's period is taken from.
const PERIODS: usize = 16;

/// How late after its regular time a target may be stamped, in periods,
/// before the stream counts as having moved its schedule (after a gap).
const MAX_LATE: f64 = 0.5;

/// Where between its regular time and its stamp a late target's position
/// is taken to be the sender's, as a share of its lateness: the middle, as
/// for a sender that reads its positions (taking the read's time) and
/// stamps them when the read is done.
const SAMPLE_SHARE: f64 = 0.5;

/// How fast the room kept for late targets shrinks once they come on time
/// again, in periods per target: slowly, so that the targets' spacing does
/// not jitter with it.
const SLACK_EASE: f64 = 0.01;

/// The piecewise-linear reference of one joint (see the module docs).
#[derive(Debug)]
pub(super) struct Reference {
    /// How many points `ahead` may hold (its room is kept from the start,
    /// clones included, so that taking points allocates nothing).
    room: usize,
    /// Where the current piece starts: (time, position).
    from: (f64, f64),
    /// The points ahead, (time, position), times increasing, after
    /// `from`.
    ahead: VecDeque<(f64, f64)>,
    /// Whether `ahead` holds a chunk's points (a single target replaces
    /// them).
    chunk: bool,
    /// The sender's stamp of the last single target.
    stamp: Option<f64>,
    /// The regular time of the last single target on the sender's clock
    /// (its stamp less how late it came after the stream's schedule).
    phase: Option<f64>,
    /// How late the last targets came after their regular times, s.
    recent: [f64; INTERVALS],
    /// The last target intervals, s (0: none), newest first.
    intervals: [f64; PERIODS],
    /// The room kept for late targets, s: the second latest of `recent`,
    /// shrinking by [`SLACK_EASE`] at most.
    slack: f64,
    /// The speed and duration of the piece before the current one, if it
    /// led into it (none after a hold or a new start).
    before: Option<(f64, f64)>,
}

impl Clone for Reference {
    fn clone(&self) -> Self {
        let mut ahead = VecDeque::with_capacity(self.room);
        ahead.extend(self.ahead.iter().copied());
        Reference { ahead, ..*self }
    }
}

impl Reference {
    /// Holding `position` from time `x`, with room for `capacity` points.
    pub fn new(x: f64, position: f64, capacity: usize) -> Self {
        Reference {
            room: capacity,
            from: (x, position),
            ahead: VecDeque::with_capacity(capacity),
            chunk: false,
            stamp: None,
            phase: None,
            recent: [0.0; INTERVALS],
            intervals: [0.0; PERIODS],
            slack: 0.0,
            before: None,
        }
    }

    /// The delay after its regular time at which a single target is
    /// reached: the stream's period ([`Reference::period`]) and how late
    /// targets come after their regular times (the second latest of the
    /// last few: one late target does not count; shrinking slowly), so
    /// that the next target is there when the reference reaches this one;
    /// 0 before any interval is known (a first target is a step).
    pub fn delay(&self) -> f64 {
        let period = self.period();
        if period == 0.0 {
            0.0
        } else {
            period + SAMPLE_SHARE * self.slack
        }
    }

    /// The second latest of the recent lateness figures, s.
    fn second_latest(&self) -> f64 {
        let mut latest = 0.0f64;
        let mut second = 0.0f64;
        for &d in &self.recent {
            if d > latest {
                second = latest;
                latest = d;
            } else if d > second {
                second = d;
            }
        }
        second
    }

    /// The stream's period: the mean of its recent intervals, those more
    /// than half again as long as their median (a gap) or half as long
    /// left out; 0 before any interval is known.
    pub fn period(&self) -> f64 {
        let mut sorted = self.intervals;
        let known = sorted.iter().filter(|d| **d > 0.0).count();
        if known == 0 {
            return 0.0;
        }
        sorted.sort_unstable_by(|a, b| b.total_cmp(a));
        let median = sorted[known / 2];
        let (mut sum, mut n) = (0.0, 0.0);
        for &d in &sorted[..known] {
            if d <= 1.5 * median && d >= 0.5 * median {
                sum += d;
                n += 1.0;
            }
        }
        sum / n
    }

    /// Takes in a target's `stamp`: its interval after the last is kept,
    /// and its regular time returned: one period after the last target's,
    /// unless it came earlier (a sender's jitter only delays: the earliest
    /// ones keep the schedule) or later by [`MAX_LATE`] periods or more
    /// (the sender moved its schedule); the schedule moves later by the
    /// least lateness of the last few targets when all of them came late
    /// (a sender whose period is a little longer than the one estimated is
    /// followed so).
    fn regular(&mut self, stamp: f64) -> f64 {
        let interval = self
            .stamp
            .map(|s| stamp - s)
            .filter(|d| *d > INTERVAL.0 && *d < INTERVAL.1);
        self.stamp = Some(stamp);
        let Some(d) = interval else {
            self.phase = Some(stamp);
            return stamp;
        };
        self.intervals.rotate_right(1);
        self.intervals[0] = d;
        let period = self.period();
        let regular = match self.phase {
            Some(last) => {
                let due = last + period;
                stamp.min(due).max(stamp - MAX_LATE * period)
            }
            None => stamp,
        };
        self.recent.rotate_right(1);
        self.recent[0] = stamp - regular;
        // Every one of the last few late: the schedule is later by the
        // least of them (a jittery sender's earliest targets keep it).
        let least = self.recent.iter().copied().fold(f64::INFINITY, f64::min);
        let regular = if least > 0.0 {
            self.recent.iter_mut().for_each(|d| *d -= least);
            self.slack -= least;
            regular + least
        } else {
            regular
        };
        self.slack = self
            .second_latest()
            .max(self.slack - SLACK_EASE * period)
            .max(0.0);
        self.phase = Some(regular);
        regular
    }

    /// The position of the reference at `x` (not before the last time
    /// it was advanced to).
    pub(super) fn position_at(&self, x: f64) -> f64 {
        match self.ahead.front() {
            Some(&(t1, p1)) => {
                let (t0, p0) = self.from;
                if t1 > t0 {
                    p0 + (p1 - p0) * ((x - t0) / (t1 - t0)).clamp(0.0, 1.0)
                } else {
                    p1
                }
            }
            None => self.from.1,
        }
    }

    /// Starts a new piece at `x` from where the reference is then, with
    /// nothing ahead.
    fn rebase(&mut self, x: f64) {
        self.advance(x);
        let p = self.position_at(x);
        self.from = (x, p);
        self.ahead.clear();
        self.chunk = false;
        self.before = None;
    }

    /// Takes in a single target at `position`, stamped `stamp` by its
    /// sender and at `at` on the run's clock, the reference having been
    /// sampled up to `x`: it is reached [`Reference::delay`] after its
    /// regular time (the stream's schedule: a jittery sender's targets are
    /// reached evenly spaced), after the points already ahead.
    pub fn target(&mut self, stamp: f64, at: f64, position: f64, x: f64) {
        let regular = self.regular(stamp);
        if self.chunk || self.ahead.is_empty() {
            self.rebase(x);
        }
        let last = self.ahead.back().map_or(self.from.0, |p| p.0);
        let taken = stamp - SAMPLE_SHARE * (stamp - regular);
        let due = (at - (stamp - taken) + self.delay()).max(last).max(x);
        if self.ahead.len() >= self.room {
            // Never with a sane stream (points are passed as fast as they
            // come); keeps the reference bounded if one floods it.
            self.ahead.pop_front();
        }
        self.ahead.push_back((due, position));
    }

    /// Replaces what is ahead by a chunk's points: `(time on the run's
    /// clock, position)`; those not after `x` (already past) are skipped.
    pub fn chunk(&mut self, points: impl Iterator<Item = (f64, f64)>, x: f64) {
        self.rebase(x);
        for (t, p) in points {
            if t > x && self.ahead.len() < self.room {
                self.ahead.push_back((t, p));
            }
        }
        self.chunk = !self.ahead.is_empty();
    }

    /// The goal at `x` (increasing from call to call) of a joint at
    /// `joint`: the reference's position, and its speed over the current
    /// piece.
    pub fn goal(&mut self, x: f64, lim: &JointLimits, joint: f64) -> Goal {
        self.advance(x);
        match self.ahead.front() {
            Some(&(t1, p1)) => {
                let (t0, p0) = self.from;
                let span = t1 - t0;
                let speed = (p1 - p0) / span;
                let cap = TARGET_SPEED_SHARE * lim.max_velocity;
                if speed.abs() > cap {
                    // Faster than the joint may follow: the reference's
                    // place, moving at the share of the speed limit a
                    // target is taken at, so that the joint goes as fast as
                    // its limits allow after it (told to rest at the
                    // piece's end instead, it would brake for it every
                    // piece); its stop is kept within the points by the
                    // follower's bounds.
                    let tau = (x - t0).clamp(0.0, span);
                    return Goal {
                        position: p0 + speed * tau,
                        velocity: cap.copysign(speed),
                        acceleration: 0.0,
                        horizon: (t1 - x).max(BEND_HORIZON),
                    };
                }
                // The piece bends as the speed changes from the piece
                // before (a parabola through both ends), so that a
                // follower told the bend keeps up with a stream that
                // speeds up or slows down; straight where it would turn
                // back inside the piece (and leave the range of its ends).
                let most = lim.max_acceleration;
                let mut accel = match self.before {
                    Some((v, d)) if span > MIN_PIECE => {
                        ((speed - v) / (0.5 * (d + span))).clamp(-most, most)
                    }
                    _ => 0.0,
                };
                let (v0, v1) = (speed - 0.5 * accel * span, speed + 0.5 * accel * span);
                // Straight too where the follower's share of the speed
                // limit caps the piece's speed (the cap bends it anyway).
                if v0 * v1 < 0.0 || !accel.is_finite() || v0.abs().max(v1.abs()) > cap {
                    accel = 0.0;
                }
                let v0 = speed - 0.5 * accel * span;
                let tau = (x - t0).max(0.0);
                let horizon = (t1 - x).max(BEND_HORIZON);
                let (pos, vel) = (p0 + tau * (v0 + 0.5 * accel * tau), v0 + accel * tau);
                // A bend that slows the goal may turn it back within the
                // horizon, which the stream, coming to rest, does not do. A
                // joint more than twice as far behind the goal as the goal
                // goes before it would rest (`v^2 / |a|`) is told the goal
                // rests at the horizon's end instead: otherwise it waits
                // for the goal's foretold return, short of where the
                // stream stopped, and comes on only when the next target
                // shows it.
                let behind = (pos - joint) * vel.signum();
                let accel = if vel * accel < 0.0
                    && vel.abs() < accel.abs() * horizon
                    && behind * accel.abs() > vel * vel
                {
                    -vel / horizon
                } else {
                    accel
                };
                Goal {
                    position: pos,
                    velocity: vel,
                    acceleration: accel,
                    // The follower keeps its speed limit over the goal's
                    // horizon, and its plan to the goal may outlast the
                    // piece: the bend is taken as lasting that long.
                    horizon,
                }
            }
            None => {
                self.chunk = false;
                Goal::at(self.from.1)
            }
        }
    }

    /// The least and greatest position the reference has between where
    /// its current piece starts and its last point ahead: every place it
    /// was told to go and has not left behind.
    pub fn reach(&self) -> (f64, f64) {
        self.ahead
            .iter()
            .fold((self.from.1, self.from.1), |(lo, hi), &(_, p)| {
                (lo.min(p), hi.max(p))
            })
    }

    /// The newest point told and the stream's speed into it, if the
    /// stream brakes into it (or turns back) harder than `max_acceleration`
    /// allows: the speeds of its last two pieces (the pieces ahead, the
    /// current one and the one before it) differ by more than that over
    /// the time between their middles. None when it does not, or when two
    /// pieces are not known.
    pub fn braking_into_newest(&self, max_acceleration: f64) -> Option<(f64, f64)> {
        let n = self.ahead.len();
        let (t2, p2) = *self.ahead.back()?;
        let (t1, p1) = if n >= 2 { self.ahead[n - 2] } else { self.from };
        let (v0, d0) = if n >= 2 {
            let (t0, p0) = if n >= 3 { self.ahead[n - 3] } else { self.from };
            ((p1 - p0) / (t1 - t0), t1 - t0)
        } else {
            self.before?
        };
        let d1 = t2 - t1;
        if d0 <= MIN_PIECE || d1 <= MIN_PIECE {
            return None;
        }
        let v1 = (p2 - p1) / d1;
        let slowing = (v0 - v1) * v0.signum();
        (slowing > max_acceleration * 0.5 * (d0 + d1)).then_some((p2, v1))
    }

    /// Passes the points due by `x`.
    fn advance(&mut self, x: f64) {
        while let Some(&(t, p)) = self.ahead.front() {
            if t > x {
                break;
            }
            let (t0, p0) = self.from;
            self.before = (t > t0 + MIN_PIECE).then(|| ((p - p0) / (t - t0), t - t0));
            self.from = (t, p);
            self.ahead.pop_front();
        }
    }

    /// Holds `position` from `x` on (nothing ahead), keeping what is known
    /// of the stream's intervals.
    pub fn restart(&mut self, x: f64, position: f64) {
        self.from = (x, position);
        self.ahead.clear();
        self.chunk = false;
        self.before = None;
    }

    /// Holds where the reference is at `x` (nothing ahead).
    pub fn hold(&mut self, x: f64) {
        self.rebase(x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIM: JointLimits = JointLimits {
        min_position: f64::NEG_INFINITY,
        max_position: f64::INFINITY,
        max_velocity: 100.0,
        max_acceleration: 1e4,
        max_jerk: None,
    };

    #[test]
    fn a_target_is_reached_one_interval_after_it_was_taken() {
        let mut r = Reference::new(0.0, 0.0, 8);
        // Targets every 30 ms on a ramp of 1 unit/s.
        for k in 1..=4 {
            let t = f64::from(k) * 0.03;
            r.target(t, t, t, t);
            let g = r.goal(t, &LIM, 0.0);
            // From the second on, the interval is known: the target is
            // reached 30 ms after its stamp, so the reference is one
            // target behind, moving at the ramp's speed.
            if k >= 3 {
                assert!((g.position - (t - 0.03)).abs() < 1e-9, "{k}: {g:?}");
                assert!((g.velocity - 1.0).abs() < 1e-9, "{k}: {g:?}");
            }
        }
        // Nothing more: it holds at the last target once reached.
        let g = r.goal(0.2, &LIM, 0.0);
        assert_eq!((g.position, g.velocity), (0.12, 0.0));
    }

    #[test]
    fn a_chunk_replaces_what_is_ahead_and_skips_its_past_points() {
        let mut r = Reference::new(0.0, 0.0, 8);
        r.chunk([(0.1, 1.0), (0.2, 2.0)].into_iter(), 0.0);
        assert!((r.goal(0.05, &LIM, 0.0).position - 0.5).abs() < 1e-9);
        // A new chunk at 0.15 whose first point is past.
        r.chunk([(0.1, 9.0), (0.25, 0.0)].into_iter(), 0.15);
        let g = r.goal(0.15, &LIM, 0.0);
        // From where the old chunk was (1.5) toward 0 at 0.25, no jump.
        assert!((g.position - 1.5).abs() < 1e-9, "{g:?}");
        assert!((g.velocity + 15.0).abs() < 1e-9, "{g:?}");
    }

    #[test]
    fn braking_into_the_newest_target_is_seen_only_beyond_the_limit() {
        // Targets every 20 ms at 1 unit/s, then one 0.004 on: 0.8 unit/s
        // less in 20 ms, 40 units/s^2 of braking.
        let mut r = Reference::new(0.0, 0.0, 8);
        for k in 1..=3 {
            let t = f64::from(k) * 0.02;
            r.target(t, t, t, t);
        }
        assert_eq!(r.braking_into_newest(10.0), None, "steady");
        r.target(0.08, 0.08, 0.064, 0.08);
        let (p, v) = r.braking_into_newest(10.0).expect("braking at 40 > 10");
        assert!(
            (p - 0.064).abs() < 1e-12 && (v - 0.2).abs() < 1e-9,
            "{p} {v}"
        );
        assert_eq!(r.braking_into_newest(50.0), None, "within 50");
    }

    #[test]
    fn one_long_gap_does_not_set_the_period_and_the_delay_relocks() {
        let mut r = Reference::new(0.0, 0.0, 8);
        let mut stamps = vec![0.0, 0.033, 0.066, 0.166];
        stamps.extend((1..=16).map(|k| 0.166 + 0.033 * f64::from(k)));
        for &s in &stamps {
            r.target(s, s, 0.0, s);
        }
        assert!((r.period() - 0.033).abs() < 1e-6, "{}", r.period());
        // Sixteen targets after the gap, on the stream's new schedule:
        // reached one period after it again.
        assert!((r.delay() - 0.033).abs() < 1e-6, "{}", r.delay());
    }

    #[test]
    fn a_jittery_senders_targets_are_reached_spaced_as_it_read_them() {
        // Every 33 ms a read of 0-6 ms, stamped when it is done (a Python
        // loop's): each position is the sender's at the middle of its
        // read, and the targets are reached spaced as those middles are
        // (within 2 ms), not as the stamps are (up to 6 ms off).
        let mut r = Reference::new(0.0, 0.0, 64);
        let read = [
            0.004, 0.0, 0.006, 0.002, 0.005, 0.001, 0.003, 0.006, 0.0, 0.004,
        ];
        let mut dues = Vec::new();
        for k in 0..40u32 {
            let slot = 0.033 * f64::from(k);
            let took = read[k as usize % read.len()];
            r.target(slot + took, slot + took, f64::from(k), slot + took);
            dues.push((slot + 0.5 * took, r.ahead.back().map_or(f64::NAN, |p| p.0)));
        }
        for w in dues[20..].windows(2) {
            let (read, reached) = (w[1].0 - w[0].0, w[1].1 - w[0].1);
            assert!((reached - read).abs() < 2e-3, "{w:?}");
        }
        // Reached one period and half the second latest lateness after the
        // schedule: the next target is in by then.
        let d = r.delay();
        assert!(d > 0.033 + 0.002 && d < 0.033 + 0.0035, "{d}");
    }
}
