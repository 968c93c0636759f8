//! Changes that make an infeasible cycle fit, and how they are ranked.

use core::fmt;
use core::time::Duration;

use crate::cost::{nanos, CycleCost, CycleSpec, Servo};
use servobus_protocol::registers::next_baud_above;

use crate::Link;

/// One change to the robot or its bus that makes the full cycle (every servo
/// written and read every cycle) fit the requested rate.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Change {
    /// Set every servo's return delay (register 7) to 0; the cycle then
    /// takes `cycle_time`.
    ReturnDelayZero {
        /// The cycle time with return delay 0.
        cycle_time: Duration,
    },
    /// Use an adapter with at most this latency per round trip (for an FTDI,
    /// lower its latency timer from the default 16 ms to 1 ms).
    LowerLatency {
        /// The highest latency that fits, rounded down to the microsecond.
        latency: Duration,
    },
    /// Raise the baud rate to `baud`, the lowest rate of the servos' table
    /// that fits.
    HigherBaud {
        /// The new baud rate.
        baud: u32,
    },
    /// Read at most `len` bytes back from each servo.
    FewerReadBytes {
        /// The most bytes per servo that fit.
        len: u8,
    },
    /// Lower the rate to `rate_hz`, the highest whole rate that fits (or the
    /// exact maximum below 1 Hz).
    LowerRate {
        /// The highest rate that fits.
        rate_hz: f64,
    },
}

impl fmt::Display for Change {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Change::ReturnDelayZero { cycle_time } => write!(
                f,
                "set the servos' return delay (register 7) to 0 (the cycle then takes {} us)",
                cycle_time.as_micros()
            ),
            Change::LowerLatency { latency } => {
                write!(
                    f,
                    "use an adapter latency of at most {} us per transaction",
                    latency.as_micros()
                )?;
                if latency >= Duration::from_millis(1) {
                    f.write_str(" (an FTDI's latency timer can be set to 1 ms)")?;
                }
                Ok(())
            }
            Change::HigherBaud { baud } => write!(f, "raise the baud rate to {baud}"),
            Change::FewerReadBytes { len } => {
                write!(f, "read at most {len} bytes back from each servo")
            }
            Change::LowerRate { rate_hz } => write!(f, "lower the rate to {rate_hz} Hz"),
        }
    }
}

/// Every [`Change`] that makes the full cycle fit, cheapest first.
///
/// The ranking puts first what costs the robot nothing and last what takes
/// something away from it: return delay 0 (a one-time setting every robot
/// should have), a lower adapter latency, a higher baud rate (a setting on
/// every servo and the adapter), fewer bytes read back (less feedback), a
/// lower rate (less control bandwidth; always possible).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Fixes {
    items: [Option<Change>; 5],
}

impl Fixes {
    /// The cheapest change, or `None` when the full cycle already fits.
    pub fn cheapest(&self) -> Option<Change> {
        self.iter().next()
    }

    /// The changes that fit, cheapest first.
    pub fn iter(&self) -> impl Iterator<Item = Change> + '_ {
        self.items.iter().flatten().copied()
    }

    /// Whether no change is needed.
    pub fn is_empty(&self) -> bool {
        self.cheapest().is_none()
    }

    /// The changes that make the full cycle of `spec` over `servos` fit
    /// `rate_hz`; empty when it already fits.
    /// `full` is `spec.cost(servos)`, already known to the caller.
    pub(crate) fn find(
        spec: &CycleSpec,
        servos: &[Servo],
        full: &CycleCost,
        rate_hz: f64,
    ) -> Fixes {
        if full.fits(rate_hz) {
            return Fixes::default();
        }
        let items = [
            return_delay_zero(spec, servos, rate_hz),
            lower_latency(spec, full, rate_hz),
            higher_baud(spec, servos, rate_hz),
            fewer_read_bytes(spec, servos, rate_hz),
            Some(Change::LowerRate {
                rate_hz: full.fastest_rate_hz(),
            }),
        ];
        Fixes { items }
    }
}

/// Return delay 0, when some servo has another and 0 makes the cycle fit.
fn return_delay_zero(spec: &CycleSpec, servos: &[Servo], rate_hz: f64) -> Option<Change> {
    if servos.iter().all(|s| s.return_delay.is_zero()) {
        return None;
    }
    let zero = CycleSpec {
        zero_return_delay: true,
        ..*spec
    }
    .cost(servos);
    zero.fits(rate_hz).then_some(Change::ReturnDelayZero {
        cycle_time: zero.cycle_time,
    })
}

/// The highest adapter latency that fits, when it is below the link's.
fn lower_latency(spec: &CycleSpec, full: &CycleCost, rate_hz: f64) -> Option<Change> {
    if full.round_trips == 0 || spec.link.latency.is_zero() {
        return None;
    }
    // cycle = rest + trips x latency <= period.
    let period = 1e9 / rate_hz;
    let rest = nanos(full.cycle_time)
        .saturating_sub(nanos(spec.link.latency).saturating_mul(full.round_trips as u64));
    let spare = period - rest as f64;
    if spare >= 0.0 {
        let per_trip_us = (spare / full.round_trips as f64 / 1_000.0).floor();
        let latency = Duration::from_micros(per_trip_us as u64);
        if latency < spec.link.latency {
            return Some(Change::LowerLatency { latency });
        }
    }
    None
}

/// The lowest baud rate of the servos' table above the link's that fits.
fn higher_baud(spec: &CycleSpec, servos: &[Servo], rate_hz: f64) -> Option<Change> {
    let mut baud = spec.link.baud;
    while let Some(next) = next_baud_above(baud) {
        let faster = CycleSpec {
            link: Link {
                baud: next,
                ..spec.link
            },
            ..*spec
        };
        if faster.cost(servos).fits(rate_hz) {
            return Some(Change::HigherBaud { baud: next });
        }
        baud = next;
    }
    None
}

/// The most bytes read back per servo that fit, when fewer than now do.
fn fewer_read_bytes(spec: &CycleSpec, servos: &[Servo], rate_hz: f64) -> Option<Change> {
    let len = spec.read_len?;
    // Fewer bytes never cost more: binary search for the largest
    // length that fits, if even 1 byte does.
    let fits = |l: u8| {
        CycleSpec {
            read_len: Some(l),
            ..*spec
        }
        .cost(servos)
        .fits(rate_hz)
    };
    if len <= 1 || !fits(1) {
        return None;
    }
    let (mut lo, mut hi) = (1u8, len - 1); // lo fits
    while lo < hi {
        let mid = lo + (hi - lo).div_ceil(2);
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    Some(Change::FewerReadBytes { len: lo })
}
