//! The commanded path of a run that follows live targets: every cycle each
//! joint takes a jerk-limited step ([`servobus_trajectory::Follower`])
//! toward its reference ([`reference`]): its position, speed and bend.
//!
//! - The reference goes through the targets received, in straight pieces,
//!   each target reached one period of the stream after it was taken (the
//!   period, and the room its late targets need, from the last few
//!   intervals: a stream's jitter and one late target do not stop it
//!   between targets). A jittery sender's targets are put on its schedule:
//!   a target stamped late (a Python loop stamps its reads when they are
//!   done) is taken as read half way between its schedule and its stamp,
//!   so that the pieces are as even as the reads were, not as the stamps.
//!   The follower is given
//!   the reference's position and speed, so that it moves with the stream
//!   rather than stopping at every target. Nothing is extrapolated past the
//!   newest target: a stream that turns back is followed back, and the
//!   commanded path leaves the envelope of the last 0.5 s of targets only
//!   by the stopping distance its limits make unavoidable ([`envelope`],
//!   measured and reported). A first target is a step: a time-optimal
//!   move to it.
//! - Where the stream brakes into its newest target harder than a joint
//!   can, the joint's stop goes no further than a joint moving with the
//!   stream there would stop (its jerk limit alone); and a joint far
//!   behind a stream that is coming to rest is not told the stream turns
//!   back, so it does not wait short of where the stream stops.
//! - A chunk (a policy's timed points) replaces what is ahead of the
//!   reference from where it is: its points are reached at their own
//!   times, those already past skipped. A single target after a chunk
//!   replaces what is left of it.
//! - The stamps are put on the run's clock by the smallest delay seen
//!   between a stamp and its arrival (relaxed by [`OFFSET_RELAX`] per
//!   target, so that a drifting sender clock is followed).
//! - No target for the timeout (counted from the last point of a chunk):
//!   every joint comes to a jerk-limited stop
//!   (where the quickest stop from its state ends) and holds. The next
//!   target resumes the following from there.
//! - Paused: the same stop and hold; targets are kept and followed on
//!   resume.
//!
//! - A wheel joint's target is a speed (rad/s, within its top speed), not
//!   a position: it is kept as given ([`LivePath::wheel_speeds`]), and the
//!   bus loop ramps the wheel toward it within its acceleration limit. A
//!   chunk gives a wheel the speed of its first point. Timed out or
//!   paused, every wheel heads for 0; a timeout also forgets the wheels'
//!   targets (a dead-man: a base that lost its stream stays stopped until
//!   a target names its wheels again), a pause keeps them for the resume.
//!
//! Stepping allocates nothing: the references keep room for a chunk of
//! [`MAX_CHUNK_POINTS`] from the start.

use servobus_trajectory::{
    stop_position, stop_with_jerk_alone, Follower, Goal, JointLimits, JointState,
};

use crate::target::{Checked, MAX_CHUNK_POINTS};

mod envelope;
mod reference;

use envelope::Envelope;
pub use envelope::EnvelopeReport;
use reference::Reference;

/// Recent commanded states kept for the reference (the commanded path at
/// the time of a reading, which lags the horizon by the lead).
const HISTORY: usize = 64;

/// How much the smallest delay between a stamp and its arrival is
/// relaxed per target, s: a sender's clock that drifts by up to 0.3 %
/// (at 30 Hz) is followed, and a stream's arrival jitter (a cycle, a
/// scheduler's few ms) does not move its targets' times.
const OFFSET_RELAX: f64 = 1e-4;

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

/// See the module documentation.
#[derive(Debug, Clone)]
pub(crate) struct LivePath {
    limits: Vec<JointLimits>,
    /// The commanded state of each joint.
    cmd: Vec<JointState>,
    followers: Vec<Follower>,
    references: Vec<Reference>,
    envelopes: Vec<Envelope>,
    /// Goals while stopped (timeout or pause).
    stops: Vec<f64>,
    /// Per joint, a wheel's target speed (rad/s); `None` for a position
    /// joint.
    speeds: Vec<Option<f64>>,
    /// Per joint, the effort of the grasp it is making (see
    /// [`crate::grasp`]); `None` when it makes none.
    grasps: Vec<Option<f64>>,
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
    /// (the run's lead), s: targets are reached that much later on the
    /// path's time, so that the path is never sampled past the newest
    /// target.
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
        let mut states = vec![JointState::default(); HISTORY * n];
        states[..n].copy_from_slice(from);
        let mut times = vec![f64::NEG_INFINITY; HISTORY];
        times[0] = x;
        let mut live = LivePath {
            cmd: from.to_vec(),
            followers: from.iter().map(|s| Follower::new(*s)).collect(),
            references: from
                .iter()
                .map(|s| Reference::new(x, s.position, MAX_CHUNK_POINTS + 1))
                .collect(),
            envelopes: from.iter().map(|s| Envelope::new(*s)).collect(),
            stops: vec![0.0; n],
            speeds: vec![None; n],
            grasps: vec![None; n],
            limits,
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

    /// Marks the wheel joints (`wheels[j]`): their targets are speeds,
    /// 0 until one comes.
    pub fn set_wheels(&mut self, wheels: &[bool]) {
        for (s, &w) in self.speeds.iter_mut().zip(wheels) {
            *s = w.then_some(0.0);
        }
    }

    /// The wheels' target speeds (rad/s) into `out` (robot order): as
    /// given while following, 0 when stopped (timeout, pause). Position
    /// joints' entries are left as they are.
    pub fn wheel_speeds(&self, out: &mut [f64]) {
        let following = self.mode == Mode::Following;
        for (o, s) in out.iter_mut().zip(&self.speeds) {
            if let Some(s) = s {
                *o = if following { *s } else { 0.0 };
            }
        }
    }

    /// The efforts of the grasps being made into `out` (robot order; `None`
    /// for a joint making none).
    pub fn grasp_efforts(&self, out: &mut [Option<f64>]) {
        for (o, g) in out.iter_mut().zip(&self.grasps) {
            *o = *g;
        }
    }

    /// Starts the grasps `grasps` (per joint, an effort) from the
    /// reference at `x`: each joint's path heads for its `min` at its
    /// closing speed ([`crate::grasp::CLOSING_SPEED_SHARE`]).
    fn grasp(&mut self, grasps: &[Option<f64>], now: f64, x: f64) {
        for (j, g) in grasps.iter().enumerate() {
            let (Some(effort), Some(l)) = (*g, self.limits.get(j)) else {
                continue;
            };
            let (Some(r), Some(e)) = (self.references.get_mut(j), self.envelopes.get_mut(j)) else {
                continue;
            };
            let from = r.position_at(x);
            let speed = crate::grasp::CLOSING_SPEED_SHARE * l.max_velocity;
            let closing = if speed > 0.0 {
                ((from - l.min_position) / speed).max(0.0)
            } else {
                0.0
            };
            // Past the closed end already: the piece ends on it at once.
            r.chunk(std::iter::once((x + closing.max(1e-3), l.min_position)), x);
            e.arrived(now, l.min_position.min(from), from.max(l.min_position));
            self.grasps[j] = Some(effort);
        }
    }

    /// Ends the grasp of every joint `t` gives a position (or a chunk's
    /// points).
    fn release_grasps(&mut self, t: &Checked) {
        let chunked = t.chunk.as_ref().map(|c| &c.joints);
        for (j, g) in self.grasps.iter_mut().enumerate() {
            let positioned = t.joints.get(j).is_some_and(Option::is_some)
                || chunked.is_some_and(|c| c.get(j).is_some_and(Option::is_some));
            if positioned {
                *g = None;
            }
        }
    }

    /// Takes in a target (or a chunk) that arrived at run time `now`.
    pub fn target(&mut self, t: &Checked, now: f64) {
        let relative = t.chunk.as_ref().is_some_and(|c| c.relative);
        let at = if relative {
            now
        } else {
            let off = now - t.stamp;
            let offset = match self.offset {
                Some(o) => (o + OFFSET_RELAX).min(off),
                None => off,
            };
            self.offset = Some(offset);
            t.stamp + offset
        } + self.lead;
        // From a stop or a pause, the reference starts where the joint is
        // heading.
        if self.mode != Mode::Following {
            for (r, s) in self.references.iter_mut().zip(&self.stops) {
                r.restart(self.last, *s);
            }
        }
        let x = self.last;
        // A chunk keeps the stream alive until its last point is due.
        let mut alive = now;
        if let Some(chunk) = &t.chunk {
            let shift = at - t.stamp;
            if let Some(end) = chunk.times.last() {
                alive = alive.max(end + shift - self.lead);
            }
            for (((r, e), q), speed) in self
                .references
                .iter_mut()
                .zip(self.envelopes.iter_mut())
                .zip(&chunk.joints)
                .zip(self.speeds.iter_mut())
            {
                let Some(q) = q else { continue };
                if let Some(speed) = speed {
                    *speed = q.first().copied().unwrap_or(0.0);
                    continue;
                }
                let (lo, hi) = q
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &p| {
                        (a.min(p), b.max(p))
                    });
                e.arrived(now, lo, hi);
                let times = chunk.times.iter().map(|s| s + shift);
                r.chunk(times.zip(q.iter().copied()), x);
            }
        } else {
            for (((r, e), new), speed) in self
                .references
                .iter_mut()
                .zip(self.envelopes.iter_mut())
                .zip(&t.joints)
                .zip(self.speeds.iter_mut())
            {
                let Some((q, _)) = *new else { continue };
                if let Some(speed) = speed {
                    *speed = q;
                    continue;
                }
                e.arrived(now, q, q);
                r.target(t.stamp, at, q, x);
            }
            self.grasp(&t.grasps, now, x);
        }
        self.release_grasps(t);
        self.arrived = alive;
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
        for ((s, c), lim) in self.stops.iter_mut().zip(&self.cmd).zip(&self.limits) {
            *s = stop_position(lim, c);
        }
    }

    /// The event of the last step, once.
    pub fn take_event(&mut self) -> Option<LiveEvent> {
        self.event.take()
    }

    /// How each joint's commanded path kept to the envelope of its targets.
    pub fn envelopes(&self) -> impl Iterator<Item = EnvelopeReport> + '_ {
        self.envelopes.iter().map(Envelope::report)
    }

    /// The goal of joint `j` at time `x`.
    fn goal(&mut self, j: usize, x: f64) -> Goal {
        if self.mode != Mode::Following {
            return Goal::at(self.stops[j]);
        }
        self.references[j].goal(x, &self.limits[j], self.cmd[j].position)
    }

    /// Where joint `j`'s reference was told to go and has not left behind
    /// ([`Reference::reach`]): its follower's stop is kept within, or
    /// within where the reference itself would stop
    /// ([`Follower::step_within`]). Unbounded while stopping (timeout,
    /// pause).
    fn bounds(&self, j: usize) -> (f64, f64) {
        if self.mode != Mode::Following {
            return (f64::NEG_INFINITY, f64::INFINITY);
        }
        self.references[j].reach()
    }

    /// How far joint `j`'s stop may follow its reference's own stop
    /// ([`Follower::step_within`]'s `farthest`). The reference is a target
    /// behind the stream: where the stream brakes into its newest target
    /// (or turns back) harder than the joint's acceleration limit allows,
    /// the reference's own stop lies beyond the stream's. Then the stop
    /// may go, on the side the stream moves to, only to where a joint
    /// moving with the stream at its newest target would stop with its
    /// jerk limit alone, and on the other side not past the points told
    /// (`bounds`). Unbounded otherwise.
    fn farthest(&self, j: usize, bounds: (f64, f64)) -> (f64, f64) {
        let lim = &self.limits[j];
        let braking = match self.mode {
            Mode::Following => self.references[j].braking_into_newest(lim.max_acceleration),
            _ => None,
        };
        let Some((position, velocity)) = braking else {
            return (f64::NEG_INFINITY, f64::INFINITY);
        };
        let newest = JointState {
            position,
            velocity,
            acceleration: 0.0,
        };
        let end = stop_with_jerk_alone(lim, &newest);
        (end.min(bounds.0), end.max(bounds.1))
    }

    /// Begins the cycle of time `now`: the timeout is judged by it.
    pub fn begin_cycle(&mut self, now: f64) {
        self.now = now;
    }

    /// The commanded state at `x` (advancing every joint to it; stopping
    /// first when no target came for the timeout before the cycle's time).
    pub fn sample_cmd(&mut self, x: f64, out: &mut [JointState]) {
        self.lead = (x - self.now).max(0.0);
        if self.mode == Mode::Following && self.now - self.arrived > self.timeout {
            self.set_stops();
            self.mode = Mode::TimedOut;
            self.event = Some(LiveEvent::TimedOut);
            for r in &mut self.references {
                r.hold(self.last);
            }
            for s in self.speeds.iter_mut().flatten() {
                *s = 0.0;
            }
        }
        let dt = x - self.last;
        if dt > 0.0 {
            // The goal at the start of the step: the follower plans from
            // there.
            for j in 0..self.cmd.len() {
                if self.speeds[j].is_some() {
                    // A wheel: its speed is the bus loop's to ramp.
                    continue;
                }
                let g = self.goal(j, self.last);
                let bounds = self.bounds(j);
                let farthest = self.farthest(j, bounds);
                let s = self.followers[j].step_within(&self.limits[j], g, dt, bounds, farthest);
                self.cmd[j] = s;
                self.envelopes[j].commanded(&self.limits[j], x, s);
            }
            self.last = x;
            let n = self.cmd.len();
            self.head = (self.head + 1) % HISTORY;
            self.times[self.head] = x;
            self.states[self.head * n..(self.head + 1) * n].copy_from_slice(&self.cmd);
        }
        for (o, c) in out.iter_mut().zip(&self.cmd) {
            *o = *c;
        }
    }

    /// The commanded path at an earlier time `x` (from the states kept,
    /// extrapolated from the latest one at or before `x`).
    pub fn sample_ref(&self, x: f64, out: &mut [JointState]) {
        let n = self.cmd.len();
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
            grasps: Vec::new(),
            taken: None,
            chunk: None,
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
    fn a_moving_target_is_followed_and_never_passed_once_it_stops() {
        // A target every 40 ms (25 Hz) until 0.48 s, followed until 0.9 s
        // (before the 1 s timeout).
        let mut rest = JointState::default();
        let mut highest = f64::NEG_INFINITY;
        let last = follow_stream(40, 480, 900, 0.0, |_, _, s| {
            rest = s;
            highest = highest.max(s.position);
        });
        assert_eq!((rest.velocity, rest.acceleration), (0.0, 0.0), "{rest:?}");
        assert!((rest.position - last).abs() < 1e-9, "{rest:?} {last}");
        // Beyond the last target by the quickest stop from 0.3 rad/s at
        // most, v sqrt(v / j) = 0.3 * sqrt(0.3 / 10000) = 1.64 mrad (by
        // hand), when the stream ends as the joint moves at its speed.
        assert!(highest - last <= 0.00165, "{}", highest - last);
    }

    #[test]
    fn a_lead_does_not_stop_the_joint_between_targets() {
        // A 50 Hz stream and a 14 ms lead, as a leader arm drives a
        // follower.
        let lead = 0.014;
        let mut slowest = f64::INFINITY;
        let mut farthest: f64 = 0.0;
        follow_stream(20, 600, 600, lead, |k, now, s| {
            if k > 200 {
                slowest = slowest.min(s.velocity);
                // One interval (20 ms) behind the stream: the lead does
                // not take the path past the newest target.
                farthest = farthest.max((s.position - 0.3 * (now - 0.020)).abs());
            }
        });
        // The joint keeps the stream's speed between targets (a stop and
        // go would fall to 0).
        assert!(slowest > 0.29, "{slowest}");
        assert!(farthest < 1e-4, "{farthest}");
    }
}
