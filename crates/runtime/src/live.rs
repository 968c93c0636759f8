//! The commanded path of a run that follows live targets: every cycle each
//! joint takes a jerk-limited step ([`servobus_trajectory::Follower`])
//! toward its newest target.
//!
//! - A moving target is followed with bounded lag: its speed is estimated
//!   from the stamps of its last two targets (or taken as given), and it is
//!   extrapolated at that speed over at most one target interval, never
//!   past a joint limit.
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
    /// The stamp, on the run's clock (s).
    at: f64,
    /// How long the target may be extrapolated, s.
    interval: f64,
    /// The sender's stamp of the last target.
    stamp: Option<f64>,
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
                at: x,
                interval: 0.0,
                stamp: None,
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
            let velocity = match (v, interval) {
                (Some(v), _) => v,
                (None, Some(d)) => (q - jt.position) / d,
                (None, None) => 0.0,
            };
            let cap = lim.max_velocity;
            *jt = JointTarget {
                position: q,
                velocity: velocity.clamp(-cap, cap),
                at,
                interval: interval.unwrap_or(if v.is_some() { INTERVAL.0 * 50.0 } else { 0.0 }),
                stamp: Some(t.stamp),
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
    fn goal(&self, j: usize, x: f64) -> Goal {
        if self.mode != Mode::Following {
            return Goal::at(self.stops[j]);
        }
        let t = &self.targets[j];
        let lim = &self.limits[j];
        let ahead = (x - t.at).clamp(0.0, t.interval);
        let moving = x - t.at < t.interval && t.velocity != 0.0;
        let q = t.position + t.velocity * ahead;
        let clamped = q.clamp(lim.min_position, lim.max_position);
        Goal {
            position: clamped,
            velocity: if moving && clamped == q {
                t.velocity
            } else {
                0.0
            },
        }
    }

    /// The commanded state at `x` (advancing every joint to it; `now` is the
    /// cycle's time, for the timeout).
    pub fn sample_cmd(&mut self, x: f64, now: f64, out: &mut [JointState]) {
        if self.mode == Mode::Following && now - self.arrived > self.timeout {
            self.set_stops();
            self.mode = Mode::TimedOut;
            self.event = Some(LiveEvent::TimedOut);
        }
        let dt = x - self.last;
        if dt > 0.0 {
            for j in 0..self.followers.len() {
                let g = self.goal(j, x);
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
