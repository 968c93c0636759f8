//! Following a moving target one control cycle at a time.
//!
//! [`Follower::step`] moves a joint's commanded state `dt` seconds toward a
//! target that moves at a constant speed or acceleration. It plans, in the
//! frame of the target (position, speed and acceleration error), the
//! time-optimal jerk-limited way to rest on the target, the same plan as
//! [`retarget`](crate::retarget) of one joint, and integrates it exactly
//! over `dt`, switches inside the cycle included. While the target stays
//! the same (moving at its constant speed) the plan is kept, so the
//! commanded motion follows one smooth profile; when the target changes,
//! the new plan starts from the state reached, with position, velocity and
//! acceleration continuous.
//!
//! Limits: the jerk stays within `max_jerk`, the acceleration within
//! `max_acceleration`, the speed within `max_velocity`: the target's own
//! speed over the goal's horizon is capped at [`TARGET_SPEED_SHARE`] of the
//! speed limit and its acceleration at [`TARGET_SPEED_SHARE`] of the
//! acceleration limit, and the plan relative to the target keeps to what
//! is left. Nothing is allocated.

use crate::online::{onward, route, stop_phases, Route1};
use crate::profile::{Acc, Phases, SIXTH};
use crate::{JointLimits, JointState};

/// The largest share of `max_velocity` a target's speed is taken at: the
/// rest is left for catching up with it.
pub const TARGET_SPEED_SHARE: f64 = 0.9;

/// Where one joint should go: a position and how it moves on (0 for a
/// fixed target): its speed and acceleration now, valid for `horizon` s.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Goal {
    /// The target position now.
    pub position: f64,
    /// The target's speed, units/s.
    pub velocity: f64,
    /// The target's acceleration, units/s^2.
    pub acceleration: f64,
    /// How long the target keeps moving so, s (the speed limit is kept
    /// over that time).
    pub horizon: f64,
}

impl Goal {
    /// A target at rest at `position`.
    pub fn at(position: f64) -> Self {
        Goal {
            position,
            ..Goal::default()
        }
    }

    /// The goal `tau` seconds on.
    fn after(&self, tau: f64) -> Goal {
        Goal {
            position: self.position + tau * (self.velocity + 0.5 * tau * self.acceleration),
            velocity: self.velocity + tau * self.acceleration,
            acceleration: self.acceleration,
            horizon: self.horizon - tau,
        }
    }
}

/// Goals closer than this (in position, and in speed per second) to the
/// one a plan was made for keep the plan.
const SAME_GOAL: f64 = 1e-9;

/// A plan in the target's frame, made at `tau = 0`.
#[derive(Debug, Clone, Copy)]
struct Plan {
    /// The goal it was made for, at `tau = 0`.
    goal: Goal,
    /// The state relative to the goal at `tau = 0`.
    err: JointState,
    pre: Phases,
    main: Phases,
    dir: f64,
    /// Time since the plan was made.
    tau: f64,
}

impl Plan {
    /// No plan yet (nothing to follow).
    const NONE: Plan = Plan {
        goal: Goal {
            position: 0.0,
            velocity: 0.0,
            acceleration: 0.0,
            horizon: 0.0,
        },
        err: JointState {
            position: 0.0,
            velocity: 0.0,
            acceleration: 0.0,
        },
        pre: Phases::new(),
        main: Phases::new(),
        dir: 1.0,
        tau: 0.0,
    };

    /// Makes this the plan from `state` to `goal` (in place: a plan is a
    /// few hundred bytes, and a cycle that replans every joint should not
    /// copy them around).
    fn renew(&mut self, lim: &JointLimits, state: &JointState, goal: Goal) {
        // The error frame: the target stands still at 0; the speed and
        // acceleration left for the error keep the sums within the joint's
        // limits.
        let rel = relative(lim, &goal);
        let err = JointState {
            position: state.position - goal.position,
            velocity: state.velocity - goal.velocity,
            acceleration: state.acceleration - goal.acceleration,
        };
        if !self.ramping(&rel, &err, goal) {
            let way = route(&err, 0.0, &rel, &mut self.pre);
            self.set(&rel, &way, err, goal, 0.0);
        }
    }

    /// Makes this the plan of `err` (relative to `goal` at `tau`) that
    /// starts with `way`, whose first phases are already in `pre`.
    fn set(&mut self, rel: &Acc, way: &Route1, err: JointState, goal: Goal, tau: f64) {
        self.main.n = 0;
        if way.seg.d > 0.0 || way.seg.v0 > 0.0 {
            way.seg.fastest_phases(rel, &mut self.main);
        }
        self.goal = goal;
        self.err = err;
        self.dir = way.dir;
        self.tau = tau;
    }

    /// A joint part way up an acceleration ramp (or down one) may be on its
    /// way to the target already: the plan made from where that ramp began
    /// (acceleration 0, `ta = |a| / j` earlier), if it starts with the same
    /// ramp for at least `ta`, goes on from here without first undoing the
    /// acceleration (which [`route`] would do, and which, planned anew
    /// every cycle, would never let the joint speed up). Returns whether
    /// this became that plan (else it is to be made anew).
    fn ramping(&mut self, rel: &Acc, err: &JointState, goal: Goal) -> bool {
        let j = rel.j;
        let ea = err.acceleration;
        if !rel.finite || ea == 0.0 {
            return false;
        }
        let ta = ea.abs() * rel.inv_j;
        let v0 = err.velocity - 0.5 * ea * ta;
        let start = JointState {
            position: err.position - v0 * ta - ea * ta * ta * SIXTH,
            velocity: v0,
            acceleration: 0.0,
        };
        // The main segment's first phase must be the ramp toward its
        // cruise speed, in the direction of `ea`, for at least `ta`: known
        // not to be before anything is solved when it must slow down (a
        // joint within its speed limit that can rest within a quarter of
        // the distance, as `onward` checks, cruises faster than it starts),
        // or when even the top speed is too close to reach in `ta` of jerk.
        // From `start` (no acceleration: `onward` has no phase before the
        // main segment) the segment starts at its speed, toward 0.
        let (dir, v0) = (if start.position <= 0.0 { 1.0 } else { -1.0 }, v0.abs());
        let slower = dir * ea < 0.0 && v0 < rel.vm;
        // The longest jerk phase the ramp may have, `min(a / j, sqrt((vm -
        // v0) / j))`, shorter than `least`: compared without dividing.
        let least = ta * (1.0 - 1e-9);
        let short = rel.a < least * j || (rel.vm - v0).max(0.0) < j * least * least;
        if slower || short {
            return false;
        }
        // A plan that stops first cannot go on with this ramp.
        let Some(way) = onward(&start, 0.0, rel, &mut self.pre) else {
            return false;
        };
        // Its first ramp lasts `ta` at least exactly when the time-optimal
        // cruise speed is `j ta^2` above `v0` at least (within the speed
        // limit, as `short` says): known from the ramps' distance at that
        // speed, before the profile is solved (a plan that would be given
        // up costs no solving).
        if !way.seg.cruises_at(rel, way.seg.v0 + j * least * least) {
            return false;
        }
        self.set(rel, &way, start, goal.after(-ta), ta);
        self.pre.n == 0
            && self.main.n > 0
            && self.main.jerk[0] * self.dir * ea > 0.0
            && self.main.dt[0] >= ta * (1.0 - 1e-9)
    }

    /// Whether `goal` (now) is the goal this plan follows.
    fn follows(&self, goal: Goal) -> bool {
        let here = self.goal.after(self.tau);
        (goal.position - here.position).abs() <= SAME_GOAL * (1.0 + here.position.abs())
            && (goal.velocity - here.velocity).abs() <= SAME_GOAL * (1.0 + here.velocity.abs())
            && goal.acceleration == here.acceleration
    }

    /// The joint's state at `tau`.
    fn at(&self, finite: bool) -> JointState {
        let (t1, p, v, a) = self.pre.advance(&self.err, 1.0, finite, self.tau);
        let mut end = JointState {
            position: p,
            velocity: v,
            acceleration: a,
        };
        if t1 < self.tau && self.main.n > 0 {
            let from = JointState {
                acceleration: 0.0,
                ..end
            };
            let (t2, p, v, a) = self.main.advance(&from, self.dir, finite, self.tau - t1);
            end = JointState {
                position: p,
                velocity: v,
                acceleration: a,
            };
            if t1 + t2 < self.tau {
                end = JointState::default();
            }
        } else if t1 < self.tau && self.main.n == 0 {
            end.acceleration = 0.0;
            end.velocity = 0.0;
        }
        let g = self.goal.after(self.tau);
        JointState {
            position: g.position + end.position,
            velocity: g.velocity + end.velocity,
            acceleration: g.acceleration + end.acceleration,
        }
    }
}

/// The limits of motion relative to `goal` (capped as [`Follower::step`]
/// does): what the goal's own motion leaves over its horizon.
fn relative(lim: &JointLimits, goal: &Goal) -> Acc {
    let end = goal.velocity + goal.acceleration * goal.horizon.max(0.0);
    Acc::of(&JointLimits {
        max_velocity: lim.max_velocity - goal.velocity.abs().max(end.abs()),
        max_acceleration: lim.max_acceleration - goal.acceleration.abs(),
        ..*lim
    })
}

/// One joint's commanded state following a goal, cycle by cycle (see the
/// module documentation). It keeps the plan it made while the goal stays
/// the same (a moving goal included), so that its motion is one smooth
/// profile, and plans anew from the state reached when the goal changes.
#[derive(Debug, Clone, Copy)]
pub struct Follower {
    state: JointState,
    plan: Plan,
    /// Whether `plan` is one (none before the first step).
    planned: bool,
}

impl Follower {
    /// A follower at `state`.
    pub fn new(state: JointState) -> Self {
        Follower {
            state,
            plan: Plan::NONE,
            planned: false,
        }
    }

    /// The commanded state.
    pub fn state(&self) -> JointState {
        self.state
    }

    /// Moves the state `dt` seconds along the jerk-limited way to `goal`
    /// and returns it. The goal's speed is capped at
    /// [`TARGET_SPEED_SHARE`] of `max_velocity`. Limits are assumed valid;
    /// a goal that is not finite, or `dt <= 0`, leaves the state unchanged.
    pub fn step(&mut self, lim: &JointLimits, goal: Goal, dt: f64) -> JointState {
        let finite_goal = goal.position.is_finite()
            && goal.velocity.is_finite()
            && goal.acceleration.is_finite()
            && !goal.horizon.is_nan();
        if !(dt > 0.0 && finite_goal) {
            return self.state;
        }
        let goal = capped(lim, goal);
        let finite = lim.max_jerk.is_some();
        if !(self.planned && self.plan.follows(goal)) {
            self.plan.renew(lim, &self.state, goal);
            self.planned = true;
        }
        self.plan.tau += dt;
        self.state = self.plan.at(finite);
        self.state
    }
}

/// How far a stop may end beyond its bound before the bound steps in, in
/// units of the bound's size (rounding of equal stops).
const BOUND_SLACK: f64 = 1e-9;

impl Follower {
    /// [`Follower::step`], kept from running past the places it was told
    /// to go. `bounds` (least, greatest) is where the goal has been told to
    /// go and has not left behind (a live reference's points).
    ///
    /// The quickest stop from the state reached must end within `bounds`,
    /// or no further than the goal's own quickest stop (where the step
    /// ends; less what the joint is ahead of the goal in the goal's
    /// direction). The goal's stop is taken with the jerk limit alone: a
    /// stream's targets may slow down harder than the joint can, and a
    /// joint allowed the goal's stop at its own acceleration limit would,
    /// catching up, run on past a goal that then braked. Where the step's
    /// stop would end further on, the step is the blend nearest the plan
    /// of it and the time-optimal way to rest on the bound whose stop is
    /// within (both keep the limits, and so does
    /// any blend of them); where even that cannot stop within (a target
    /// that turned back faster than the limits allow), the joint brakes as
    /// hard as its limits let it and comes back. So a joint on its goal
    /// is held back only where its speed is beyond what its jerk limit
    /// stops without reaching its acceleration limit (`a^2 / j`), by the
    /// difference of those stops; one catching up after a turn does it no
    /// faster than it could stop where the goal would, and does not run
    /// past the next turn; one that has turned back already is left to its
    /// plan.
    ///
    /// `farthest` (least, greatest) is as far as the goal's own stop may
    /// take the bounds: the caller's knowledge of where the stream could
    /// stop (for a live stream, where a joint moving with it at its newest
    /// target would); unbounded: `(-inf, inf)`.
    pub fn step_within(
        &mut self,
        lim: &JointLimits,
        goal: Goal,
        dt: f64,
        bounds: (f64, f64),
        farthest: (f64, f64),
    ) -> JointState {
        let from = self.state;
        let s = self.step(lim, goal, dt);
        // (Bounds that are not numbers, or crossed, bound nothing.)
        let ordered = matches!(
            bounds.0.partial_cmp(&bounds.1),
            Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
        );
        if s == from || !ordered {
            return s;
        }
        let end = stop_position(lim, &s);
        let own = goal_stop(lim, capped(lim, goal).after(dt), s.position);
        // (A `farthest` that is not numbers bounds nothing.)
        let (far_lo, far_hi) = (farthest.0.min(farthest.1), farthest.1.max(farthest.0));
        let own = if far_lo <= far_hi {
            own.clamp(far_lo, far_hi)
        } else {
            own
        };
        let (lo, hi) = (bounds.0.min(own), bounds.1.max(own));
        let slack = BOUND_SLACK * (1.0 + lo.abs().max(hi.abs()));
        // Only a stop further on than the state itself.
        let edge = if end > hi + slack && end > s.position {
            hi
        } else if end < lo - slack && end < s.position {
            lo
        } else {
            return s;
        };
        self.plan.renew(lim, &from, Goal::at(edge));
        self.plan.tau += dt;
        let rest = self.plan.at(lim.max_jerk.is_some());
        let within = |x: &JointState| {
            let e = stop_position(lim, x);
            e <= hi + slack && e >= lo - slack
        };
        if within(&rest) {
            self.state = nearest_within(&rest, &s, within);
            // The state is on neither plan: the next step plans anew.
            self.planned = false;
        } else {
            self.state = rest;
        }
        self.state
    }
}

/// Where a joint at `position` may let its stop run to, following `goal`
/// (the goal where the step ends, as the state is): the goal's own
/// quickest stop, less what the joint is ahead of the goal in the goal's
/// direction ([`Follower::step_within`]).
///
/// A stream's targets may slow down harder than the joint can: the goal's
/// own stop is taken with its jerk limit alone (no acceleration limit), so
/// that a joint catching up with a goal that then brakes hard does not run
/// on past it. A joint ahead of its goal has that much less room: the goal
/// comes to it, and it does not run on past the places it was told to
/// match the goal's speed.
#[inline]
fn goal_stop(lim: &JointLimits, goal: Goal, position: f64) -> f64 {
    let own = stop_with_jerk_alone(
        lim,
        &JointState {
            position: goal.position,
            velocity: goal.velocity,
            acceleration: goal.acceleration,
        },
    );
    let dir = if goal.velocity > 0.0 {
        1.0
    } else if goal.velocity < 0.0 {
        -1.0
    } else {
        0.0
    };
    let ahead = ((position - goal.position) * dir).max(0.0);
    own - ahead * dir
}

/// The blend of `rest` (whose stop is `within`) and `step` nearest `step`
/// whose stop is still within, found by halving ([`BLEND_STEPS`]). Both
/// steps start from the same state and keep the limits over the cycle, and
/// so does any blend of them (the jerk of a blend is the blend of the
/// jerks).
#[inline]
fn nearest_within(
    rest: &JointState,
    step: &JointState,
    within: impl Fn(&JointState) -> bool,
) -> JointState {
    let blend = |k: f64| JointState {
        position: rest.position + k * (step.position - rest.position),
        velocity: rest.velocity + k * (step.velocity - rest.velocity),
        acceleration: rest.acceleration + k * (step.acceleration - rest.acceleration),
    };
    let (mut ok, mut bad) = (0.0, 1.0);
    for _ in 0..BLEND_STEPS {
        let k = 0.5 * (ok + bad);
        if within(&blend(k)) {
            ok = k;
        } else {
            bad = k;
        }
    }
    blend(ok)
}

/// Halvings of the blend between a step and the bound's ([`Follower::step_within`]).
const BLEND_STEPS: usize = 8;

/// `goal` with its acceleration and its speed over its horizon capped at
/// [`TARGET_SPEED_SHARE`] of the limits.
fn capped(lim: &JointLimits, goal: Goal) -> Goal {
    let acap = TARGET_SPEED_SHARE * lim.max_acceleration;
    let vcap = TARGET_SPEED_SHARE * lim.max_velocity;
    let a = goal.acceleration.clamp(-acap, acap);
    let v = goal.velocity.clamp(-vcap, vcap);
    let h = goal.horizon.max(0.0);
    // The speed at the end of the horizon within the cap too (dividing
    // only when it is not: most goals are well within).
    let end = v + a * h;
    let a = if h <= 0.0 {
        0.0
    } else if end > vcap {
        (vcap - v) / h
    } else if end < -vcap {
        (-vcap - v) / h
    } else {
        a
    };
    Goal {
        position: goal.position,
        velocity: v,
        acceleration: a,
        horizon: h,
    }
}

/// Where the quickest jerk-limited stop from `state` ends (the stop of
/// [`stop`](crate::stop)).
pub fn stop_position(lim: &JointLimits, state: &JointState) -> f64 {
    let mut ph = Phases::new();
    stop_phases(state.velocity, state.acceleration, &Acc::of(lim), &mut ph);
    ph.advance(state, 1.0, lim.max_jerk.is_some(), f64::INFINITY)
        .1
}

/// Where the quickest stop from `state` ends with the jerk limit alone
/// (no acceleration limit): how far a stream's target, which may brake
/// harder than the joint, goes before it rests. With no jerk limit, the
/// stop of [`stop_position`].
#[inline]
pub fn stop_with_jerk_alone(lim: &JointLimits, state: &JointState) -> f64 {
    let hard = match lim.max_jerk {
        Some(_) => JointLimits {
            max_acceleration: f64::INFINITY,
            ..*lim
        },
        None => *lim,
    };
    stop_position(&hard, state)
}

/// [`Follower::step`] for every joint.
pub fn follow_steps(limits: &[JointLimits], followers: &mut [Follower], goals: &[Goal], dt: f64) {
    for ((lim, f), g) in limits.iter().zip(followers.iter_mut()).zip(goals) {
        f.step(lim, *g, dt);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lim() -> JointLimits {
        JointLimits::new(2.0, 10.0, Some(100.0))
    }

    /// No bound on the goal's own stop.
    const ANY: (f64, f64) = (f64::NEG_INFINITY, f64::INFINITY);

    /// Steps to a fixed goal; returns every state.
    fn run(from: JointState, goal: Goal, dt: f64, n: usize) -> Vec<JointState> {
        let mut f = Follower::new(from);
        (0..n).map(|_| f.step(&lim(), goal, dt)).collect()
    }

    #[test]
    fn a_step_is_reached_at_rest_within_the_limits() {
        let dt = 0.005;
        let states = run(JointState::at_rest(0.0), Goal::at(1.0), dt, 400);
        let last = states[states.len() - 1];
        assert!((last.position - 1.0).abs() < 1e-9, "{last:?}");
        assert!(last.velocity.abs() < 1e-9 && last.acceleration.abs() < 1e-9);
        for w in states.windows(2) {
            assert!(w[1].velocity.abs() <= 2.0 + 1e-9);
            assert!(w[1].acceleration.abs() <= 10.0 + 1e-9);
            let jerk = (w[1].acceleration - w[0].acceleration) / dt;
            assert!(jerk.abs() <= 100.0 + 1e-6, "{jerk}");
        }
        // Never beyond the target.
        assert!(states.iter().all(|s| s.position <= 1.0 + 1e-9));
    }

    #[test]
    fn a_moving_target_is_caught_and_followed_at_its_speed() {
        let dt = 0.005;
        let mut f = Follower::new(JointState::at_rest(0.0));
        let mut s = f.state();
        for k in 0..400 {
            let t = k as f64 * dt;
            let goal = Goal {
                position: 0.2 + 0.5 * t,
                velocity: 0.5,
                acceleration: 0.0,
                horizon: 1.0,
            };
            s = f.step(&lim(), goal, dt);
        }
        // After the step the target is at 0.2 + 0.5 * 2.0.
        assert!((s.position - 1.2).abs() < 1e-6, "{s:?}");
        assert!((s.velocity - 0.5).abs() < 1e-6, "{s:?}");
    }

    #[test]
    fn a_joint_on_its_goal_is_not_held_back_by_its_bounds() {
        let dt = 0.005;
        let (mut free, mut bound) = (
            Follower::new(JointState::at_rest(0.0)),
            Follower::new(JointState::at_rest(0.0)),
        );
        for k in 0..400 {
            let t = k as f64 * dt;
            let goal = Goal {
                position: 0.5 * t,
                velocity: 0.5,
                acceleration: 0.0,
                horizon: 1.0,
            };
            // The places told: from where the goal is to one interval
            // (30 ms) ahead of it.
            let a = free.step(&lim(), goal, dt);
            let b = bound.step_within(&lim(), goal, dt, (0.5 * t, 0.5 * (t + 0.03)), ANY);
            if k > 300 {
                // Caught up (no faster than it could stop where the goal
                // would: later than without bounds), on the goal within
                // half a millisecond of its motion, moving with it.
                assert!((b.position - a.position).abs() < 2.5e-4, "{k}: {a:?} {b:?}");
                assert!((b.velocity - 0.5).abs() < 1e-3, "{k}: {b:?}");
            }
        }
    }

    #[test]
    fn a_turn_is_overrun_by_no_more_than_the_stop_it_forces() {
        // A goal moving up at 1.5 units/s that turns back at 1.0: told
        // nothing beyond 1.0, the joint goes past it by its quickest stop
        // from where it was when the turn came, and not further (without
        // bounds it catches up with the goal's speed and goes further).
        let dt = 0.005;
        let mut f = Follower::new(JointState::at_rest(0.0));
        let (mut turned, mut highest) = (None, f64::NEG_INFINITY);
        for k in 0..600 {
            let t = k as f64 * dt;
            let (goal, bounds) = if 1.5 * t < 1.0 {
                (
                    Goal {
                        position: 1.5 * t,
                        velocity: 1.5,
                        acceleration: 0.0,
                        horizon: 1.0,
                    },
                    (0.0, (1.5 * t + 0.05).min(1.0)),
                )
            } else {
                let back = 1.0 - 1.5 * (t - 1.0 / 1.5);
                (
                    Goal {
                        position: back,
                        velocity: -1.5,
                        acceleration: 0.0,
                        horizon: 1.0,
                    },
                    (back - 0.05, 1.0),
                )
            };
            if turned.is_none() && 1.5 * t >= 1.0 {
                turned = Some(stop_position(&lim(), &f.state()));
            }
            let s = f.step_within(&lim(), goal, dt, bounds, ANY);
            if k % 50 == 0 {
                // The speed limit is kept (the goal's own is 1.5 of 2).
                assert!(s.velocity.abs() <= 2.0 + 1e-9, "{s:?}");
            }
            highest = highest.max(s.position);
        }
        let allowed = turned.expect("it turned");
        assert!(allowed > 1.0, "{allowed}");
        assert!(highest <= allowed + 1e-9, "{highest} beyond {allowed}");
    }

    #[test]
    fn bad_input_changes_nothing() {
        let mut f = Follower::new(JointState::at_rest(0.3));
        f.step(&lim(), Goal::at(f64::NAN), 0.01);
        f.step(&lim(), Goal::at(1.0), 0.0);
        assert_eq!(f.state(), JointState::at_rest(0.3));
    }
}
