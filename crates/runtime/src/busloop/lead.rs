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
    },
}

impl LeadEstimator {
    /// The estimator for `lead`.
    pub fn new(lead: Lead) -> Self {
        LeadEstimator(match lead {
            Lead::None => State::Fixed(0.0),
            Lead::Fixed(d) => State::Fixed(d.as_secs_f64()),
            Lead::Auto { max } => State::Auto {
                max: max.as_secs_f64(),
                sev: 0.0,
                svv: 0.0,
                n: 0,
                // No lead until the first estimate (a finished ramp to 0).
                ramp: Ramp {
                    from: 0.0,
                    to: 0.0,
                    x0: f64::NEG_INFINITY,
                },
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
