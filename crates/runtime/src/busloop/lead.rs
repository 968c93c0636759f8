//! Lead (lag compensation): how far ahead of the path the goals are
//! commanded, fixed or identified from the tracking errors while the path
//! plays (see [`Lead`]).

use crate::options::Lead;

/// How long the lead takes at least to ramp in once identified, s.
const LEAD_RAMP_S: f64 = 0.5;
/// How far a change of the lead may take the goals past a path's speed,
/// acceleration and jerk, as a fraction of the joint's limit.
///
/// Goals are the path sampled `lead` ahead: at path time `x` the goal is
/// `p(x + l(x))`. While the lead ramps, the goals' speed is `(1 + l') v`,
/// their acceleration `(1 + l')^2 a + l'' v` and their jerk
/// `(1 + l')^3 j + 3 (1 + l') l'' a + l''' v`: a path planned at a joint's
/// limits is commanded past them by the ramp's derivatives. Each ramp is
/// long enough ([`Pace::span`]) that each kind of extra term takes at most
/// a third of this.
pub(crate) const LEAD_EXCESS: f64 = 0.01;

/// The quintic ramp's peak first, second and third derivatives for a
/// change of 1 over a span of 1: 15/8, 10/sqrt(3) and 60.
const RAMP_PEAKS: [f64; 3] = [1.875, 5.773_502_691_896_258, 60.0];

/// What a bus's joints allow, for the lead's ramps: the largest ratios of
/// a joint's speed limit to its acceleration limit and to its jerk limit,
/// and of its acceleration limit to its jerk limit (0 for a joint with no
/// jerk limit).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Pace {
    /// Max over the joints of `max_velocity / max_acceleration`, s.
    pub v_over_a: f64,
    /// Max of `max_velocity / max_jerk`, s^2.
    pub v_over_j: f64,
    /// Max of `max_acceleration / max_jerk`, s.
    pub a_over_j: f64,
}

impl Pace {
    /// The ratios of the joints' limits `(velocity, acceleration, jerk)`.
    pub fn of(limits: impl Iterator<Item = (f64, f64, Option<f64>)>) -> Self {
        let ratio = |x: f64, y: f64| if y > 0.0 && y.is_finite() { x / y } else { 0.0 };
        let mut p = Pace::default();
        for (v, a, j) in limits {
            p.v_over_a = p.v_over_a.max(ratio(v, a));
            if let Some(j) = j {
                p.v_over_j = p.v_over_j.max(ratio(v, j));
                p.a_over_j = p.a_over_j.max(ratio(a, j));
            }
        }
        p
    }

    /// The shortest span (s) over which a change of the lead by `delta`
    /// keeps each kind of extra term of the goals' derivatives within a
    /// third of [`LEAD_EXCESS`] of the joint's limit.
    fn span(&self, delta: f64) -> f64 {
        let d = delta.abs();
        let share = LEAD_EXCESS / 3.0;
        let [r1, r2, r3] = RAMP_PEAKS;
        // Speed: 3 r1 d / T <= share, so that even the jerk's (1 + l')^3
        // stays within its share.
        let speed = 3.0 * r1 * d / share;
        // Acceleration: r2 d / T^2 x v <= share x a.
        let accel = (r2 * d * self.v_over_a / share).sqrt();
        // Jerk: 3 r2 d / T^2 x a and r3 d / T^3 x v, each within half the
        // share of j.
        let jerk = (6.0 * r2 * d * self.a_over_j / share)
            .sqrt()
            .max((2.0 * r3 * d * self.v_over_j / share).cbrt());
        speed.max(accel).max(jerk)
    }
}
/// Readings of moving joints needed before the lag is (re-)estimated.
const IDENTIFY_READINGS: u32 = 60;
/// Smallest change of the identified lag that moves the lead, s.
const LEAD_STEP: f64 = 0.000_5;
/// Slowest path speed that counts for identification, rad/s: the error of a
/// joint at rest says nothing about its lag.
const IDENTIFY_MIN_SPEED: f64 = 0.05;

/// A smooth change of the lead from `from` to `to`, starting at `x0`.
#[derive(Debug, Clone, Copy)]
struct Ramp {
    from: f64,
    to: f64,
    x0: f64,
    /// How long it takes, s.
    span: f64,
}

impl Ramp {
    /// A ramp from `from` to `to` starting at `x0`, over at least
    /// [`LEAD_RAMP_S`] and slow enough for [`LEAD_EXCESS`] on joints of
    /// `pace`.
    fn new(from: f64, to: f64, x0: f64, pace: &Pace) -> Self {
        let span = pace.span(to - from).max(LEAD_RAMP_S);
        Ramp { from, to, x0, span }
    }

    fn at(&self, x: f64) -> f64 {
        let u = ((x - self.x0) / self.span).clamp(0.0, 1.0);
        self.from + (self.to - self.from) * u * u * u * (10.0 + u * (-15.0 + 6.0 * u))
    }

    fn done(&self, x: f64) -> bool {
        x >= self.x0 + self.span
    }
}

/// The lead of one bus.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LeadEstimator(State);

#[derive(Debug, Clone, Copy)]
enum State {
    Fixed(f64),
    /// Identified while the path plays, and refined: every
    /// [`IDENTIFY_READINGS`] readings the estimate is updated and, when it
    /// moved, the lead ramps to it.
    Auto {
        max: f64,
        /// Sum of (error + lead x velocity) x velocity over the readings:
        /// the error against the path is velocity x (lag - lead), so this
        /// estimates the lag whatever lead was in force.
        sev: f64,
        svv: f64,
        /// Readings since the estimate was last updated.
        n: u32,
        ramp: Ramp,
        /// The joints' limits, for the ramps.
        pace: Pace,
        /// Whether an estimate was made (else the lead is the prior).
        estimated: bool,
    },
}

/// The lag a bus's goals see before anything is identified, s: the
/// slowest of its servos' response lags (the protocol crate's per-model
/// fact), plus the loop's own delay, half a `period` on average (a goal is
/// held for the whole cycle it is written in).
pub(crate) fn prior_lag(lags: impl Iterator<Item = std::time::Duration>, period: f64) -> f64 {
    lags.map(|d| d.as_secs_f64()).fold(0.0, f64::max) + period / 2.0
}

impl LeadEstimator {
    /// The estimator for `lead`, starting from the lag `prior` (s; see
    /// [`prior_lag`]) when it identifies the lag, on joints of `pace`.
    pub fn new(lead: Lead, prior: f64, pace: Pace) -> Self {
        LeadEstimator(match lead {
            Lead::None => State::Fixed(0.0),
            Lead::Fixed(d) => State::Fixed(d.as_secs_f64()),
            Lead::Auto { max } => State::Auto {
                max: max.as_secs_f64(),
                sev: 0.0,
                svv: 0.0,
                n: 0,
                // The prior is in force from the first cycle, until the
                // first estimate: every run starts at rest (a path from
                // its first keyframe, an approach, a hold), where a lead
                // moves the goal by nothing, so there is no step to ramp.
                ramp: {
                    let prior = prior.clamp(0.0, max.as_secs_f64());
                    Ramp::new(prior, prior, 0.0, &pace)
                },
                pace,
                estimated: false,
            },
        })
    }

    /// The lead at path time `x`, s.
    pub fn at(&self, x: f64) -> f64 {
        match &self.0 {
            State::Fixed(l) => *l,
            State::Auto { ramp, .. } => ramp.at(x),
        }
    }

    /// Whether the lead was identified from the run's motion (at least one
    /// estimate made); a fixed lead, or one still at its prior, was not.
    pub fn identified(&self) -> bool {
        matches!(
            self.0,
            State::Auto {
                estimated: true,
                ..
            }
        )
    }

    /// Learns from one cycle's `(error, planned velocity)` readings at time
    /// `t`; `main` says whether a planned path is playing (only its motion
    /// identifies the lag: approaches and stops are too short and slow).
    pub fn learn(&mut self, readings: impl Iterator<Item = (f64, f64)>, main: bool, t: f64) {
        let lead = self.at(t);
        let State::Auto {
            max,
            sev,
            svv,
            n,
            ramp,
            pace,
            estimated,
        } = &mut self.0
        else {
            return;
        };
        if main {
            // The cycle's sums first, then the run's: as the figures in the
            // tests were measured.
            let (mut ev, mut vv, mut count) = (0.0, 0.0, 0);
            for (e, v) in readings.filter(|(_, v)| v.abs() > IDENTIFY_MIN_SPEED) {
                ev += (e + lead * v) * v;
                vv += v * v;
                count += 1;
            }
            *sev += ev;
            *svv += vv;
            *n += count;
        }
        // A new estimate once enough readings came in and the last change
        // has finished; small changes are not worth a ramp.
        if *n >= IDENTIFY_READINGS && *svv > 0.0 && ramp.done(t) {
            *n = 0;
            *estimated = true;
            let lag = (*sev / *svv).clamp(0.0, *max);
            if (lag - ramp.to).abs() > LEAD_STEP {
                *ramp = Ramp::new(ramp.to, lag, t, pace);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;

    #[test]
    fn the_prior_is_the_slowest_servo_plus_half_a_cycle() {
        let ms = Duration::from_millis;
        // 10 ms and 8 ms servos at 200 Hz: 10 + 5 / 2 = 12.5 ms.
        let prior = prior_lag([ms(10), ms(8)].into_iter(), 0.005);
        assert!((prior - 0.0125).abs() < 1e-12, "{prior}");
        // It is in force from the first cycle, before any reading.
        let auto = LeadEstimator::new(Lead::default(), prior, Pace::default());
        assert!((auto.at(0.0) - 0.0125).abs() < 1e-12);
        assert!((auto.at(0.25) - 0.0125).abs() < 1e-12);
        // Bounded by the largest lead allowed, and unused by a fixed lead.
        let capped = LeadEstimator::new(Lead::Auto { max: ms(5) }, prior, Pace::default());
        assert!((capped.at(1.0) - 0.005).abs() < 1e-12);
        assert_eq!(
            LeadEstimator::new(Lead::None, prior, Pace::default()).at(0.0),
            0.0
        );
    }
}
