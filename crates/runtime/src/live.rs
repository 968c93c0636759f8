//! The commanded path of a run that follows live targets: every cycle each
//! joint takes a jerk-limited step ([`servobus_trajectory::Follower`])
//! toward its newest target.
//!
//! - A moving target is followed with bounded lag: its speed and
//!   acceleration are estimated from three of its targets by their stamps,
//!   the newest and the ones about [`SPAN`] and half of it before (so that
//!   a fast stream of noisy readings, a leader arm's, gives steady
//!   estimates; a 30 Hz stream uses its last three), or the speed is taken
//!   as given. The target is extrapolated so over at most one target
//!   interval (the longest of the last [`INTERVALS`], so that a target a
//!   little late after a short interval does not count as the end of the
//!   motion; none before two targets have given an interval), never past
//!   a joint limit. The interval counts from the target's stamp on the
//!   run's clock, the run's lead added: the commanded path is sampled that
//!   far ahead of the cycle (to make up for the servos' response lag), and
//!   a lead taken out of the interval would bring the joint to rest before
//!   every target of a stream whose interval is not much longer than the
//!   lead (a 50 Hz leader arm and a 14 ms lead: stop and go).
//!   Once the extrapolation ends the joint goes to rest there, or, when it
//!   cannot stop before, where its quickest stop ends: it never turns back
//!   for a target that stopped abruptly.
//! - The stamps are put on the run's clock by the smallest delay seen
//!   between a stamp and its arrival (relaxed by 1 ms per target, so that
//!   a drifting sender clock is followed).
//! - No target for the timeout: every joint comes to a jerk-limited stop
//!   (where the quickest stop from its state ends) and holds. The next
//!   target resumes the following from there.
//! - Paused: the same stop and hold; targets are kept and followed on
//!   resume.
//!
//! Stepping allocates nothing.

use servobus_trajectory::{stop_position, Follower, Goal, JointLimits, JointState};

use crate::target::Checked;

/// Recent commanded states kept for the reference (the commanded path at
/// the time of a reading, which lags the horizon by the lead).
const HISTORY: usize = 64;

/// Stamp differences outside this range give no speed estimate, s.
const INTERVAL: (f64, f64) = (0.001, 0.5);

/// How many recent target intervals the extrapolation horizon is the
/// longest of.
const INTERVALS: usize = 4;

/// The least time the speed and acceleration of a target are estimated
/// over, s. The acceleration of a parabola through three readings grows
/// with their noise over the span squared: over 40 ms, a leader arm's
/// readings (0.088 deg ticks at 50 Hz) gave accelerations of some
/// hundreds of deg/s^2 from tick noise alone, and a follower that wandered
/// by 1-2 deg about a steadily moving leader.
const SPAN: f64 = 0.08;

/// How many past targets a joint keeps for the estimates.
const KEPT: usize = 16;

/// What the following of live targets did ([`Telemetry::Live`](crate::Telemetry::Live)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum LiveEvent {
    /// No target for the timeout: stopping.
    TimedOut,
    /// Targets came back after a timeout.
    Resumed,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    Following,
    /// Stopped for lack of targets.
    TimedOut,
    Paused,
}

/// One joint's newest target.
#[derive(Debug, Clone, Copy)]
struct JointTarget {
    position: f64,
    velocity: f64,
    acceleration: f64,
    /// The last targets' `(stamp, position)`, newest first.
    history: [(f64, f64); KEPT],
    /// How many of `history` are filled.
    kept: usize,
    /// The stamp, on the run's clock (s).
    at: f64,
    /// How long the target may be extrapolated, s.
    interval: f64,
    /// The last intervals between targets, s (0: none).
    recent: [f64; INTERVALS],
    /// The sender's stamp of the last target.
    stamp: Option<f64>,
    /// Where the joint rests once the extrapolation has ended (chosen
    /// then, kept until the next target).
    rest: Option<f64>,
}

/// The speed at the newest of `history` (`(stamp, position)`, newest
/// first) and the acceleration: the parabola through the newest, the
/// newest at least [`SPAN`] older (else the oldest) and the one nearest the
/// middle of the two; a straight line with two targets; nothing with one.
fn estimate(history: &[(f64, f64)]) -> (f64, f64) {
    let Some(&(s2, q2)) = history.first() else {
        return (0.0, 0.0);
    };
    let Some(i0) = (1..history.len())
        .find(|&i| s2 - history[i].0 >= SPAN)
        .or_else(|| history.len().checked_sub(1).filter(|&i| i > 0))
    else {
        return (0.0, 0.0);
    };
    let (s0, q0) = history[i0];
    if i0 == 1 {
        return ((q2 - q0) / (s2 - s0), 0.0);
    }
    let mid = 0.5 * (s0 + s2);
    let i1 = (1..i0)
        .min_by(|&a, &b| {
            (history[a].0 - mid)
                .abs()
                .total_cmp(&(history[b].0 - mid).abs())
        })
        .unwrap_or(1);
    let (s1, q1) = history[i1];
    let (d1, d2) = ((q1 - q0) / (s1 - s0), (q2 - q1) / (s2 - s1));
    let a = 2.0 * (d2 - d1) / (s2 - s0);
    (d2 + 0.5 * a * (s2 - s1), a)
}

/// See the module documentation.
#[derive(Debug, Clone)]
pub(crate) struct LivePath {
    limits: Vec<JointLimits>,
    followers: Vec<Follower>,
    targets: Vec<JointTarget>,
    /// Goals while stopped (timeout or pause).
    stops: Vec<f64>,
    mode: Mode,
    /// Whether any target has come.
    any: bool,
    /// Time of the latest commanded state.
    last: f64,
    /// The run's time of the latest target's arrival.
    arrived: f64,
    /// The time of the cycle being run ([`LivePath::begin_cycle`]).
    now: f64,
    /// How far ahead of the cycle's time the commanded path is sampled
    /// (the run's lead), s.
    lead: f64,
    timeout: f64,
    /// Run time minus sender stamp, smallest seen (relaxed).
    offset: Option<f64>,
    /// Ring of `(time, states)` of recent commanded states.
    times: Vec<f64>,
    states: Vec<JointState>,
    head: usize,
    event: Option<LiveEvent>,
}

impl LivePath {
    /// Following from `from` (commanded state at time `x`), holding it
    /// until a target comes; `timeout` s without targets stops.
    pub fn new(limits: Vec<JointLimits>, from: &[JointState], x: f64, timeout: f64) -> Self {
        let n = limits.len();
        let targets = from
            .iter()
            .map(|s| JointTarget {
                position: s.position,
                velocity: 0.0,
                acceleration: 0.0,
                history: [(0.0, 0.0); KEPT],
                kept: 0,
                at: x,
                interval: 0.0,
                recent: [0.0; INTERVALS],
                stamp: None,
                rest: None,
            })
            .collect();
        let mut states = vec![JointState::default(); HISTORY * n];
        states[..n].copy_from_slice(from);
        let mut times = vec![f64::NEG_INFINITY; HISTORY];
        times[0] = x;
        let mut live = LivePath {
            followers: from.iter().map(|s| Follower::new(*s)).collect(),
            stops: vec![0.0; n],
            limits,
            targets,
            mode: Mode::TimedOut,
            any: false,
            last: x,
            arrived: x,
            now: x,
            lead: 0.0,
            timeout,
            offset: None,
            times,
            states,
            head: 0,
            event: None,
        };
        // Until the first target: stop (when switched from a moving path)
        // and hold.
        live.set_stops();
        live
    }

    /// Takes in a target that arrived at run time `now`.
    pub fn target(&mut self, t: &Checked, now: f64) {
        let off = now - t.stamp;
        let offset = match self.offset {
            Some(o) => (o + 0.001).min(off),
            None => off,
        };
        self.offset = Some(offset);
        let at = t.stamp + offset;
        for ((jt, new), lim) in self.targets.iter_mut().zip(&t.joints).zip(&self.limits) {
            let Some((q, v)) = *new else { continue };
            let dt = jt.stamp.map(|s| t.stamp - s);
            let interval = dt.filter(|d| *d > INTERVAL.0 && *d < INTERVAL.1);
            let mut history = jt.history;
            let kept = if interval.is_some() {
                history.rotate_right(1);
                (jt.kept + 1).min(KEPT)
            } else {
                1
            };
            history[0] = (t.stamp, q);
            let (mean, accel) = estimate(&history[..kept]);
            let cap = lim.max_acceleration;
            let accel = if accel.is_finite() {
                accel.clamp(-cap, cap)
            } else {
                0.0
            };
            let velocity = match v {
                Some(v) => v,
                None if mean.is_finite() => mean,
                None => 0.0,
            };
            let cap = lim.max_velocity;
            let mut recent = jt.recent;
            recent.rotate_right(1);
            recent[0] = interval.unwrap_or(0.0);
            let longest = recent.iter().copied().fold(0.0, f64::max);
            *jt = JointTarget {
                position: q,
                velocity: velocity.clamp(-cap, cap),
                acceleration: if v.is_some() { 0.0 } else { accel },
                history,
                kept,
                at,
                // One target interval at most: the longest of the last
                // few (jitter makes some shorter than the stream's), none
                // before an interval is known.
                interval: if interval.is_some() { longest } else { 0.0 },
                recent,
                stamp: Some(t.stamp),
                rest: None,
            };
        }
        self.arrived = now;
        if self.mode == Mode::TimedOut {
            self.mode = Mode::Following;
            if self.any {
                self.event = Some(LiveEvent::Resumed);
            }
        }
        self.any = true;
    }

    /// Pauses (stop and hold) or resumes the following.
    pub fn pause(&mut self, paused: bool) {
        if paused && self.mode != Mode::Paused {
            self.set_stops();
            self.mode = Mode::Paused;
        } else if !paused && self.mode == Mode::Paused {
            self.mode = Mode::Following;
        }
    }

    fn set_stops(&mut self) {
        for ((s, f), lim) in self.stops.iter_mut().zip(&self.followers).zip(&self.limits) {
            *s = stop_position(lim, &f.state());
        }
    }

    /// The event of the last step, once.
    pub fn take_event(&mut self) -> Option<LiveEvent> {
        self.event.take()
    }

    /// The goal of joint `j` at time `x`.
    fn goal(&mut self, j: usize, x: f64) -> Goal {
        if self.mode != Mode::Following {
            return Goal::at(self.stops[j]);
        }
        // The few numbers the goal needs, not a copy of the target and its
        // history.
        let t = &self.targets[j];
        let lim = self.limits[j];
        if let Some(rest) = t.rest {
            return Goal::at(rest);
        }
        // The extrapolation's reach, counted from the stamp: one interval
        // beyond the cycle the path is sampled for.
        let reach = t.interval + self.lead;
        let ahead = (x - t.at).clamp(0.0, reach);
        let moving = x - t.at < reach && (t.velocity != 0.0 || t.acceleration != 0.0);
        let q = t.position + ahead * (t.velocity + 0.5 * ahead * t.acceleration);
        let clamped = q.clamp(lim.min_position, lim.max_position);
        if moving && clamped == q {
            return Goal {
                position: q,
                velocity: t.velocity + ahead * t.acceleration,
                acceleration: t.acceleration,
                horizon: reach - ahead,
            };
        }
        // At rest at the end of the extrapolation, unless the joint cannot
        // stop before it: then where its quickest stop ends.
        let s = self.followers[j].state();
        let stop = stop_position(&lim, &s);
        let beyond = (stop - clamped) * s.velocity > 0.0;
        let rest = if beyond {
            stop.clamp(lim.min_position, lim.max_position)
        } else {
            clamped
        };
        self.targets[j].rest = Some(rest);
        Goal::at(rest)
    }

    /// Begins the cycle of time `now`: the timeout is judged by it.
    pub fn begin_cycle(&mut self, now: f64) {
        self.now = now;
    }

    /// The commanded state at `x` (advancing every joint to it; stopping
    /// first when no target came for the timeout before the cycle's time).
    /// `x` past the cycle's time is the run's lead.
    pub fn sample_cmd(&mut self, x: f64, out: &mut [JointState]) {
        self.lead = (x - self.now).max(0.0);
        if self.mode == Mode::Following && self.now - self.arrived > self.timeout {
            self.set_stops();
            self.mode = Mode::TimedOut;
            self.event = Some(LiveEvent::TimedOut);
        }
        let dt = x - self.last;
        if dt > 0.0 {
            // The goal at the start of the step: the follower plans from
            // there.
            for j in 0..self.followers.len() {
                let g = self.goal(j, self.last);
                self.followers[j].step(&self.limits[j], g, dt);
            }
            self.last = x;
            let n = self.followers.len();
            self.head = (self.head + 1) % HISTORY;
            self.times[self.head] = x;
            for (s, f) in self.states[self.head * n..(self.head + 1) * n]
                .iter_mut()
                .zip(&self.followers)
            {
                *s = f.state();
            }
        }
        for (o, f) in out.iter_mut().zip(&self.followers) {
            *o = f.state();
        }
    }

    /// The commanded path at an earlier time `x` (from the states kept,
    /// extrapolated from the latest one at or before `x`).
    pub fn sample_ref(&self, x: f64, out: &mut [JointState]) {
        let n = self.followers.len();
        let mut best = self.head;
        for k in 0..HISTORY {
            let i = (self.head + HISTORY - k) % HISTORY;
            if self.times[i] == f64::NEG_INFINITY {
                break;
            }
            best = i;
            if self.times[i] <= x {
                break;
            }
        }
        let dt = (x - self.times[best]).max(0.0);
        for (o, s) in out.iter_mut().zip(&self.states[best * n..(best + 1) * n]) {
            *o = JointState {
                position: s.position + dt * (s.velocity + 0.5 * dt * s.acceleration),
                velocity: s.velocity + dt * s.acceleration,
                acceleration: s.acceleration,
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A target putting joint 0 at `q` rad, stamped `stamp` s.
    fn at(stamp: f64, q: f64) -> Checked {
        Checked {
            stamp,
            joints: vec![Some((q, None))],
            taken: None,
        }
    }

    /// Follows a target moving at 0.3 rad/s, sent every `every` cycles up
    /// to cycle `until`, at 1 kHz for `cycles` cycles, the path sampled
    /// `lead` s ahead of each cycle; `seen` gets each cycle's number, time
    /// and commanded state. Returns the last target.
    fn follow_stream(
        every: u32,
        until: u32,
        cycles: u32,
        lead: f64,
        mut seen: impl FnMut(u32, f64, JointState),
    ) -> f64 {
        // Limits far above the target's motion, so that the joint keeps up
        // with it and rests where its goal does.
        let lim = JointLimits::new(10.0, 100.0, Some(10_000.0));
        let mut live = LivePath::new(vec![lim], &[JointState::at_rest(0.0)], 0.0, 1.0);
        let mut out = [JointState::default()];
        let mut last = f64::NAN;
        for k in 1..=cycles {
            let now = f64::from(k) * 0.001;
            live.begin_cycle(now);
            if k % every == 0 && k <= until {
                last = 0.3 * now;
                live.target(&at(now, last), now);
            }
            live.sample_cmd(now + lead, &mut out);
            seen(k, now, out[0]);
        }
        last
    }

    #[test]
    fn a_moving_target_is_extrapolated_over_one_target_interval_at_most() {
        // A target every 40 ms (25 Hz) until 0.48 s, followed until 0.9 s
        // (before the 1 s timeout).
        let mut rest = JointState::default();
        let last = follow_stream(40, 480, 900, 0.0, |_, _, s| rest = s);
        assert_eq!((rest.velocity, rest.acceleration), (0.0, 0.0), "{rest:?}");
        // One interval on: 12 mrad past the last target. The joint may go
        // on for its quickest stop from 0.3 rad/s, v sqrt(v / j) = 0.3 *
        // sqrt(0.3 / 10000) = 1.64 mrad, plus one cycle's motion, 0.3 mrad
        // (by hand). One and a half intervals would be 18 mrad.
        let past = rest.position - last;
        assert!(past >= 0.012 - 1e-9, "{past}");
        assert!(past <= 0.012 + 0.00165 + 0.0003, "{past}");
    }

    #[test]
    fn a_lead_is_not_taken_out_of_the_extrapolation() {
        // A 50 Hz stream and a 14 ms lead, as a leader arm drives a
        // follower: 14 of every 20 ms lie beyond one interval from the
        // stamp if the lead counts against it.
        let lead = 0.014;
        let mut slowest = f64::INFINITY;
        let mut farthest: f64 = 0.0;
        follow_stream(20, 600, 600, lead, |k, now, s| {
            if k > 200 {
                slowest = slowest.min(s.velocity);
                // Where the stream is at the horizon, by hand.
                farthest = farthest.max((s.position - 0.3 * (now + lead)).abs());
            }
        });
        // The joint keeps the stream's speed between targets (a stop and
        // go would fall to 0) and is where the stream is at the horizon.
        assert!(slowest > 0.29, "{slowest}");
        assert!(farthest < 1e-4, "{farthest}");
    }
}
