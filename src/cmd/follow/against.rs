//! The follower's error against its leader. The leader is read at 50 Hz
//! and the follower at its own rate, each reading at its own time: the
//! newest of one compared with the newest of the other mixes two times,
//! and on a loaded machine their gap grows into a false error. Instead,
//! each reading of a follower joint is compared with the leader's pose at
//! that reading's own time, interpolated between the leader's readings
//! around it. Both arms' readings are stamped on the process's one clock
//! (`servobus_robot::system_clock`), with the time the servo took them
//! (`Bus::heard`, `JointSample::measured_at`).

use std::collections::VecDeque;
use std::time::Duration;

use servobus_config::Units;
use servobus_robot::CycleSample;

/// Errors of the follower against the leader are counted from this time
/// on, s (the follower first catches up with wherever the leader is).
pub(super) const ERRORS_FROM: f64 = 0.5;

/// How much of the leader's past is kept, s: a follower reading older than
/// that when it is looked at is not counted (the live channel delivers
/// within a few cycles).
const KEEP_S: f64 = 1.0;

/// The leader's readings of the last [`KEEP_S`], per follower joint:
/// `(time s, angle rad)`, oldest first.
pub(super) struct LeaderTrail {
    joints: Vec<VecDeque<(f64, f64)>>,
}

impl LeaderTrail {
    /// A trail of `n` follower joints, empty.
    pub fn new(n: usize) -> Self {
        LeaderTrail {
            joints: vec![VecDeque::new(); n],
        }
    }

    /// Follower joint `joint`'s leader read `angle` (rad) at `at` (s).
    pub fn push(&mut self, joint: usize, at: f64, angle: f64) {
        let Some(q) = self.joints.get_mut(joint) else {
            return;
        };
        // A time that goes back (it cannot, on one monotonic clock) would
        // break the interpolation's order: such a reading is dropped.
        if q.back().is_some_and(|&(t, _)| at < t) {
            return;
        }
        q.push_back((at, angle));
        while q.front().is_some_and(|&(t, _)| t < at - KEEP_S) {
            q.pop_front();
        }
    }

    /// The leader's angle for follower joint `joint` at `t` (s), linearly
    /// between the readings around it; `None` outside the trail.
    pub fn at(&self, joint: usize, t: f64) -> Option<f64> {
        let q = self.joints.get(joint)?;
        let after = q.partition_point(|&(s, _)| s < t);
        let &(t1, a1) = q.get(after)?;
        if t1 == t {
            return Some(a1);
        }
        let &(t0, a0) = q.get(after.checked_sub(1)?)?;
        Some(a0 + (a1 - a0) * (t - t0) / (t1 - t0))
    }

    /// The newest reading's time of follower joint `joint`.
    fn newest(&self, joint: usize) -> Option<f64> {
        self.joints.get(joint)?.back().map(|&(t, _)| t)
    }

    /// The oldest reading's time of follower joint `joint`.
    fn oldest(&self, joint: usize) -> Option<f64> {
        self.joints.get(joint)?.front().map(|&(t, _)| t)
    }
}

/// The error figures of one joint: sum of squares, largest, count.
pub(super) type Figures = (f64, f64, u64);

/// The follower's readings waiting for the leader's readings after them,
/// and the error figures so far.
pub(super) struct FollowErrors {
    figures: Vec<Figures>,
    /// The time of the last reading queued per joint (a sample repeats a
    /// reading until the next one).
    last: Vec<Duration>,
    /// `(joint, time s, measured angle in the robot's units)`.
    pending: VecDeque<(usize, f64, f64)>,
    /// Readings before this time (s) are not counted.
    from: f64,
}

impl FollowErrors {
    /// Figures of `n` joints, counting nothing until
    /// [`count_from`](Self::count_from) is told when to start.
    pub fn new(n: usize) -> Self {
        FollowErrors {
            figures: vec![(0.0, 0.0, 0); n],
            last: vec![Duration::ZERO; n],
            pending: VecDeque::new(),
            from: f64::INFINITY,
        }
    }

    /// Counts the readings taken from `from` (s, on the clock the readings
    /// are stamped on) on.
    pub fn count_from(&mut self, from: f64) {
        self.from = from;
    }

    /// Queues the new readings of a telemetry sample.
    pub fn sample(&mut self, s: &CycleSample) {
        for j in s.joints() {
            let (Some(m), Some(last)) = (j.measured, self.last.get_mut(j.joint)) else {
                continue;
            };
            if j.measured_at <= *last {
                continue;
            }
            *last = j.measured_at;
            let t = j.measured_at.as_secs_f64();
            if t >= self.from {
                self.pending.push_back((j.joint, t, m));
            }
        }
    }

    /// Counts every queued reading the leader's trail now covers; the
    /// others wait for the leader's next reading, unless the trail has
    /// already moved past them.
    pub fn settle(&mut self, trail: &LeaderTrail, units: Units) {
        let mut keep = 0;
        for k in 0..self.pending.len() {
            let (joint, t, m) = self.pending[k];
            if !trail.newest(joint).is_some_and(|newest| t <= newest) {
                self.pending[keep] = self.pending[k];
                keep += 1;
                continue;
            }
            if trail.oldest(joint).is_some_and(|oldest| t < oldest) {
                continue;
            }
            if let (Some(p), Some(f)) = (trail.at(joint, t), self.figures.get_mut(joint)) {
                let d = units.from_rad(p) - m;
                *f = (f.0 + d * d, f.1.max(d.abs()), f.2 + 1);
            }
        }
        self.pending.truncate(keep);
    }

    /// Each joint's figures, in the follower's joint order.
    pub fn figures(&self) -> &[Figures] {
        &self.figures
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_leader_is_interpolated_at_the_followers_reading_time() {
        let mut trail = LeaderTrail::new(1);
        trail.push(0, 1.00, 0.0);
        trail.push(0, 1.02, 0.2);
        trail.push(0, 1.04, 0.2);
        // By hand: a quarter of the way from 0 to 0.2, then on a reading,
        // then flat; outside the trail, nothing.
        assert!((trail.at(0, 1.005).unwrap_or(f64::NAN) - 0.05).abs() < 1e-12);
        assert_eq!(trail.at(0, 1.02), Some(0.2));
        assert_eq!(trail.at(0, 1.03), Some(0.2));
        assert_eq!(trail.at(0, 0.99), None);
        assert_eq!(trail.at(0, 1.05), None);
        assert_eq!(trail.at(1, 1.01), None);
        // Readings older than a second are let go.
        trail.push(0, 2.03, 0.3);
        assert_eq!(trail.at(0, 1.02), None);
        assert_eq!(trail.at(0, 1.04), Some(0.2));
    }
}
