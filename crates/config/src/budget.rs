//! Whether a control rate fits a bus, from servobus-timing's cycle plan.

use core::fmt;
use core::time::Duration;

use servobus_timing::{plan, Block, Change, CycleError, Link, Plan, Servo};

use super::BusConfig;

impl BusConfig {
    /// The servos of this bus as the timing planner sees them, in joint order.
    pub fn timing_servos(&self) -> Vec<Servo> {
        self.joints
            .iter()
            .map(|j| Servo::new(j.id, self.return_delay, j.model.series.has_sync_read()))
            .collect()
    }

    /// The link as the budget charges it before anything is measured: the
    /// robot file's baud rate and adapter latency (0 for `latency_us:
    /// auto`), and on the built-in simulator (a bus without a `port:`) the
    /// pseudo-terminal's cost of each exchange ([`Link::on_pty`]). A
    /// program that measured the adapter plans on
    /// [`measured_link`](BusConfig::measured_link) instead.
    pub fn budget_link(&self) -> Link {
        let link = self.link();
        if self.port.is_none() {
            link.on_pty()
        } else {
            link
        }
    }

    /// The link of this bus on a port whose adapter was measured (the
    /// start-up probe of `latency_us: auto`, PINGs): `ping_latency` is the
    /// median of what each PING took beyond the wire and the servo, which is
    /// the adapter's latency and every per-exchange overhead of the link
    /// together. On a pseudo-terminal (`servobus sim`) each further reply
    /// of a SYNC READ costs [`Link::PTY_REPLY_OVERHEAD`] more, which a PING
    /// (one reply) shows only once.
    pub fn measured_link(&self, ping_latency: Duration, pty: bool) -> Link {
        let link = Link::new(self.baud);
        if pty {
            link.with_latency(ping_latency.saturating_sub(Link::PTY_REPLY_OVERHEAD))
                .with_overhead(Duration::ZERO, Link::PTY_REPLY_OVERHEAD)
        } else {
            link.with_latency(ping_latency)
        }
    }

    /// The plan of this bus's control cycle at `rate_hz` on the link of
    /// [`budget_link`](BusConfig::budget_link): goal positions written to
    /// every servo (SYNC WRITE), present positions read back (SYNC READ, or
    /// one READ per servo without it). When the full cycle does not fit,
    /// the plan reads a round-robin subset each cycle and lists what would
    /// make it fit.
    ///
    /// # Errors
    ///
    /// [`CycleError`] when not even the round-robin cycle fits (it names the
    /// cheapest change that would), or the rate is not positive.
    pub fn plan(&self, rate_hz: f64) -> Result<Plan, CycleError> {
        self.plan_on(&self.budget_link(), rate_hz)
    }

    /// As [`plan`](BusConfig::plan), on `link` (a measured one, see
    /// [`measured_link`](BusConfig::measured_link)).
    ///
    /// # Errors
    ///
    /// As [`plan`](BusConfig::plan).
    pub fn plan_on(&self, link: &Link, rate_hz: f64) -> Result<Plan, CycleError> {
        let (write, read) = self.cycle_blocks();
        plan(
            link,
            &self.timing_servos(),
            Some(write),
            Some(read),
            rate_hz,
        )
    }

    /// What a cycle writes to each servo and reads back: the goal position
    /// and the present position; on a bus with wheel joints the present
    /// speed too (read with the position), and the write charged as goal
    /// position, time and speed for every servo (more than the goal
    /// positions and the wheels' goal speeds in their two frames, so the
    /// plan never promises a rate the cycle cannot hold).
    pub fn cycle_blocks(&self) -> (Block, Block) {
        if self.joints.iter().any(|j| j.is_wheel()) {
            let read = Block::span(
                servobus_protocol::registers::sts::PRESENT_POSITION.register(),
                servobus_protocol::registers::sts::PRESENT_SPEED.register(),
            );
            (Block::POSITION_TIME_SPEED, read)
        } else {
            (Block::GOAL_POSITION, Block::PRESENT_POSITION)
        }
    }

    /// The fastest whole rate at which every servo is read every cycle, Hz
    /// (the one figure `budget`, `play` and `bench` all print), or `None`
    /// when the bus cannot be planned at all.
    pub fn fastest_rate_hz(&self) -> Option<f64> {
        self.fastest_rate_hz_on(&self.budget_link())
    }

    /// As [`fastest_rate_hz`](BusConfig::fastest_rate_hz), on `link`.
    pub fn fastest_rate_hz_on(&self, link: &Link) -> Option<f64> {
        // The full cycle's cost does not depend on the rate.
        self.plan_on(link, f64::MIN_POSITIVE)
            .ok()
            .map(|p| p.fastest_rate_hz())
    }

    /// The plan at `rate_hz` if it may run on this bus: the full cycle fits,
    /// or it does not but the bus allows reading servos round-robin
    /// ([`round_robin`](BusConfig::round_robin)) and a round-robin cycle fits.
    ///
    /// # Errors
    ///
    /// [`RateError`], which names the fastest rate that fits.
    pub fn check_rate(&self, rate_hz: f64) -> Result<Plan, RateError> {
        self.check_rate_on(&self.budget_link(), rate_hz)
    }

    /// As [`check_rate`](BusConfig::check_rate), on `link` (a measured
    /// one, see [`measured_link`](BusConfig::measured_link)): the check of
    /// the rate once the adapter is known, against the maximum `budget
    /// --port` prints.
    ///
    /// # Errors
    ///
    /// As [`check_rate`](BusConfig::check_rate).
    pub fn check_rate_on(&self, link: &Link, rate_hz: f64) -> Result<Plan, RateError> {
        match self.plan_on(link, rate_hz) {
            Ok(p) if p.read_every() == 1 || self.round_robin => Ok(p),
            Ok(p) => Err(RateError::AboveMaximum {
                rate_hz,
                fastest_hz: p.fastest_rate_hz(),
                read_every: p.read_every(),
            }),
            Err(source) => Err(RateError::Unplannable {
                source,
                fastest_hz: self.fastest_rate_hz_on(link),
            }),
        }
    }
}

/// Why a control rate may not run on a bus.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RateError {
    /// The full cycle (every servo read every cycle) does not fit, and the
    /// bus does not allow reading servos round-robin.
    #[error(
        "{rate_hz} Hz is above the maximum rate of {fastest_hz} Hz: the full cycle does not fit \
         (it would read each servo only every {read_every} cycles)"
    )]
    AboveMaximum {
        /// The rate asked for.
        rate_hz: f64,
        /// The fastest whole rate at which the full cycle fits.
        fastest_hz: f64,
        /// How often each servo would be read at `rate_hz`.
        read_every: usize,
    },
    /// Not even a round-robin cycle fits (or the bus cannot be planned).
    #[error("{source}")]
    Unplannable {
        /// The planner's reason.
        source: CycleError,
        /// The fastest whole rate at which the full cycle fits, if any.
        fastest_hz: Option<f64>,
    },
}

impl RateError {
    /// The fastest whole rate that fits the full cycle, if the bus has one.
    pub fn fastest_hz(&self) -> Option<f64> {
        match *self {
            RateError::AboveMaximum { fastest_hz, .. } => Some(fastest_hz),
            RateError::Unplannable { fastest_hz, .. } => fastest_hz,
        }
    }

    /// The error with its advice: the fastest rate that fits, and (where it
    /// helps) reading the bus's servos round-robin, said in the robot file's
    /// terms. A program that has its own switch for it adds that itself
    /// ([`RateError::round_robin_helps`]).
    pub fn with_advice(&self) -> impl fmt::Display + '_ {
        Advised(self)
    }

    /// Whether reading the bus's servos round-robin (one per cycle instead
    /// of all) would let the rate fit.
    pub fn round_robin_helps(&self) -> bool {
        matches!(self, RateError::AboveMaximum { .. })
    }
}

struct Advised<'a>(&'a RateError);

impl fmt::Display for Advised<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Advised(error) = *self;
        write!(f, "{error}")?;
        let Some(fastest) = error.fastest_hz() else {
            return Ok(());
        };
        if let RateError::Unplannable {
            source:
                CycleError::Infeasible {
                    fix: Change::LowerRate { .. },
                    ..
                },
            ..
        } = error
        {
            // The planner's advice already is that rate.
            return Ok(());
        }
        write!(f, "; the fastest rate that fits is {fastest} Hz")?;
        if error.round_robin_helps() {
            f.write_str(
                ", or set `round_robin: true` on the bus in the robot file to read servos \
                 round-robin",
            )?;
        }
        Ok(())
    }
}
