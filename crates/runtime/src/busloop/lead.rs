//! Lead (lag compensation): how far ahead of the path the goals are
//! commanded, fixed or identified from the tracking errors while the path
//! plays (see [`Lead`]).

use crate::options::Lead;

/// How long the lead takes to ramp in once identified, s.
const LEAD_RAMP_S: f64 = 0.5;
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
}

impl Ramp {
    fn at(&self, x: f64) -> f64 {
        let u = ((x - self.x0) / LEAD_RAMP_S).clamp(0.0, 1.0);
        self.from + (self.to - self.from) * u * u * u * (10.0 + u * (-15.0 + 6.0 * u))
    }

    fn done(&self, x: f64) -> bool {
        x >= self.x0 + LEAD_RAMP_S
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
    /// [`prior_lag`]) when it identifies the lag.
    pub fn new(lead: Lead, prior: f64) -> Self {
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
                    Ramp {
                        from: prior,
                        to: prior,
                        x0: 0.0,
                    }
                },
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
                *ramp = Ramp {
                    from: ramp.to,
                    to: lag,
                    x0: t,
                };
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
        let auto = LeadEstimator::new(Lead::default(), prior);
        assert!((auto.at(0.0) - 0.0125).abs() < 1e-12);
        assert!((auto.at(0.25) - 0.0125).abs() < 1e-12);
        // Bounded by the largest lead allowed, and unused by a fixed lead.
        let capped = LeadEstimator::new(Lead::Auto { max: ms(5) }, prior);
        assert!((capped.at(1.0) - 0.005).abs() < 1e-12);
        assert_eq!(LeadEstimator::new(Lead::None, prior).at(0.0), 0.0);
    }
}
