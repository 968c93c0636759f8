//! Measuring a bus: how fast a full cycle (a SYNC WRITE of every servo's
//! goal and a SYNC READ of every position) really runs on it, against what
//! the wire allows, with each servo's round trip.
//!
//! The servos are held where they are (their goals are their present
//! positions): nothing moves.

use std::time::Duration;

use serde::Serialize;
use servobus_config::BusConfig;
use servobus_driver::{
    Bus, BusError, Clock, MissingReason, Transport, PATIENT_TRIES, PROBE_CEILING, PROBE_PINGS,
};
use servobus_protocol::registers::{addr, Register, Series, ValueError};
use servobus_runtime::stats::Histogram;
pub use servobus_runtime::Quantiles;
use servobus_timing::{CycleError, Link};

/// One servo's round trip, us.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ServoRtt {
    /// Its ID.
    pub id: u8,
    /// Its joint.
    pub joint: String,
    /// Replies measured.
    pub replies: u64,
    /// Mean round trip, us.
    pub rtt_mean_us: f64,
    /// Longest round trip, us.
    pub rtt_max_us: f64,
    /// Replies it did not give in time.
    pub timeouts: u64,
}

/// One bus's figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BusBench {
    /// The bus.
    pub name: String,
    /// Its servos.
    pub servos: usize,
    /// What it ran on (a serial port, the simulator on a pty); the caller's
    /// to fill in.
    pub backend: String,
    /// Whether replies were waited for by polling.
    pub busy_poll: bool,
    /// Full cycles run.
    pub cycles: u64,
    /// Cycles per second achieved.
    pub achieved_rate_hz: f64,
    /// The highest rate the cycle's plan allows.
    pub planned_rate_hz: f64,
    /// The rate the wire alone would allow.
    pub wire_limited_rate_hz: f64,
    /// The cycles' periods, us.
    pub period_us: Quantiles,
    /// Each period against the mean period, us.
    pub period_error_us: Quantiles,
    /// Cycles whose period exceeded the planned cycle time.
    pub overruns: u64,
    /// The pty's own request/reply floor for this cycle, mean rate (on the
    /// simulator only; 0 on a serial port); the caller's to fill in.
    pub floor_rate_hz: f64,
    /// Achieved over floor rate (0 without a floor).
    pub floor_ratio: f64,
    /// On a port: the median of what each PING of the start-up probe took
    /// beyond the wire and the servo, us, on which `planned_rate_hz` is
    /// planned (as `budget --port` plans); the caller's to fill in.
    pub measured_latency_us: Option<f64>,
    /// Replies not given in time (and not late either).
    pub timeouts: u64,
    /// Replies that came after their deadline: the servo answered, the
    /// host delivered late.
    pub late_replies: u64,
    /// Transactions retried.
    pub retries: u64,
    /// Servos missing from a SYNC READ.
    pub missed_replies: u64,
    /// Replies with a bad checksum.
    pub checksum_errors: u64,
    /// Each servo's round trip.
    pub servo_rtt: Vec<ServoRtt>,
}

/// Why a bus could not be measured.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BenchError {
    /// The bus has no joints to measure with.
    #[error("bus `{bus}` has no joints")]
    NoJoints {
        /// The bus.
        bus: String,
    },
    /// Its cycle cannot be planned.
    #[error("bus `{bus}`: cannot plan its cycle")]
    Plan {
        /// The bus.
        bus: String,
        /// Why.
        #[source]
        source: CycleError,
    },
    /// The servos' register map has no present position.
    #[error("register map has no present position")]
    NoPositionRegister,
    /// A transaction failed (`what`: the first read, SYNC WRITE, SYNC READ).
    #[error("bus `{bus}`: {what}")]
    Bus {
        /// The bus.
        bus: String,
        /// What was being done.
        what: &'static str,
        /// The bus's error.
        #[source]
        source: BusError,
    },
    /// A servo did not answer the first, patient read.
    #[error("bus `{bus}`: servo {id} does not answer ({reason}) after {tries} tries")]
    Missing {
        /// The bus.
        bus: String,
        /// The servo.
        id: u8,
        /// Why, at the last try.
        reason: MissingReason,
        /// How many times it was asked.
        tries: u8,
    },
    /// A servo reported a position its register cannot hold.
    #[error("a servo reported an impossible position")]
    Position(#[source] ValueError),
}

/// How long, after a cycle with servos missing, the bench waits for their
/// late replies before the next request: against `servobus sim` on a
/// busy two-core machine, replies reached the host up to 20 ms after their
/// deadline (the simulator or the kernel's pty hand-off descheduled).
pub const LATE_REPLY_WAIT: Duration = Duration::from_millis(25);

/// What the start-up probe measured of the link to a bus's servos.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasuredLink {
    /// The link to plan on ([`BusConfig::measured_link`]).
    pub link: Link,
    /// The median of what each PING took beyond the wire and the servo
    /// (the typical exchange: one stall of a loaded host does not move it).
    pub ping_latency: Duration,
    /// PINGs answered.
    pub pings: u32,
}

/// Measures the link to `bus`'s servos on `servo_bus` with the start-up
/// probe of `latency_us: auto` ([`Bus::probe_latency`], the same PINGs a
/// run sends), and gives the link its cycle costs on. `pty`: the port is
/// a pseudo-terminal (`servobus sim`), whose replies cost a hand-off each.
///
/// # Errors
/// [`BenchError::NoJoints`]; [`BenchError::Bus`] when no servo answers.
pub fn measure_link<T: Transport>(
    servo_bus: &mut Bus<T>,
    bus: &BusConfig,
    pty: bool,
) -> Result<MeasuredLink, BenchError> {
    let ids: Vec<u8> = bus.joints.iter().map(|j| j.id).collect();
    if ids.is_empty() {
        return Err(BenchError::NoJoints {
            bus: bus.name.clone(),
        });
    }
    let m = servo_bus
        .probe_latency(&ids, PROBE_PINGS, PROBE_CEILING, |_| {})
        .map_err(|source| BenchError::Bus {
            bus: bus.name.clone(),
            what: "measuring the adapter",
            source,
        })?;
    Ok(MeasuredLink {
        link: bus.measured_link(m.median, pty),
        ping_latency: m.median,
        pings: m.samples,
    })
}

/// Runs full cycles on `servo_bus`, the bus `bus` of a robot, for
/// `duration`, holding every servo where the first (untimed, patient) read
/// finds it, and returns the figures, planned on the budget's link
/// ([`BusConfig::budget_link`]). `backend` and the floor are left for the
/// caller.
///
/// # Errors
/// A [`BenchError`] naming the bus and what failed.
pub fn measure<T: Transport>(
    servo_bus: &mut Bus<T>,
    bus: &BusConfig,
    duration: Duration,
) -> Result<BusBench, BenchError> {
    measure_on(servo_bus, bus, &bus.budget_link(), duration)
}

/// As [`measure`], with the planned figures on `link` (a measured one,
/// see [`measure_link`]).
///
/// # Errors
/// A [`BenchError`] naming the bus and what failed.
pub fn measure_on<T: Transport>(
    servo_bus: &mut Bus<T>,
    bus: &BusConfig,
    link: &Link,
    duration: Duration,
) -> Result<BusBench, BenchError> {
    let ids: Vec<u8> = bus.joints.iter().map(|j| j.id).collect();
    let Some(first) = bus.joints.first() else {
        return Err(BenchError::NoJoints {
            bus: bus.name.clone(),
        });
    };
    let series = first.model.series;
    let plan = bus.plan_on(link, 1.0).map_err(|source| BenchError::Plan {
        bus: bus.name.clone(),
        source,
    })?;
    let pos = series
        .map()
        .at(addr::PRESENT_POSITION)
        .ok_or(BenchError::NoPositionRegister)?;
    let goals = hold_goals(servo_bus, bus, &ids, pos, series)?;
    servo_bus.reset_counters();
    let run = run_cycles(servo_bus, bus, &ids, &goals, pos, duration)?;
    // An overrun: a cycle that took longer than the plan says a full cycle
    // takes (the period it would have at the maximum rate).
    let overruns = overruns(&run.period_list, plan.full_cycle().cycle_time);
    let counters = *servo_bus.counters();
    Ok(BusBench {
        name: bus.name.clone(),
        servos: ids.len(),
        backend: String::new(),
        busy_poll: bus.busy_poll,
        cycles: run.cycles,
        achieved_rate_hz: run.achieved_rate_hz(),
        planned_rate_hz: plan.max_rate_hz(),
        wire_limited_rate_hz: plan.wire_limited_rate_hz(),
        period_us: Quantiles::of(&run.periods, Duration::from_micros(1)),
        period_error_us: Quantiles::of(&run.period_errors(), Duration::from_micros(1)),
        overruns,
        floor_rate_hz: 0.0,
        floor_ratio: 0.0,
        measured_latency_us: None,
        timeouts: counters.timeouts,
        late_replies: counters.late_replies,
        retries: counters.retries,
        missed_replies: run.missed,
        checksum_errors: counters.checksum_errors,
        servo_rtt: servo_rtts(servo_bus, bus),
    })
}

/// The error of a failed `what` on `bus`, from the bus's.
fn failed<'b>(bus: &'b BusConfig, what: &'static str) -> impl FnOnce(BusError) -> BenchError + 'b {
    move |source| BenchError::Bus {
        bus: bus.name.clone(),
        what,
        source,
    }
}

/// The goals that hold every servo `ids` where it is: their present
/// positions (register `pos`), in the layout of this bus's `series`.
fn hold_goals<T: Transport>(
    servo_bus: &mut Bus<T>,
    bus: &BusConfig,
    ids: &[u8],
    pos: &Register,
    series: Series,
) -> Result<Vec<u8>, BenchError> {
    let len = usize::from(pos.size);
    let mut goals = vec![0u8; ids.len() * len];
    // The first read is not timed: a loaded machine or a slow adapter gets
    // a patient timeout and a few tries before a servo counts as absent.
    let read = servo_bus
        .sync_read_patiently(pos.address, pos.size, ids)
        .map_err(failed(bus, "first read"))?;
    for (i, reply) in read.iter().enumerate() {
        match reply {
            Ok(r) => goals[i * len..(i + 1) * len].copy_from_slice(r.data),
            Err(missing) => {
                return Err(BenchError::Missing {
                    bus: bus.name.clone(),
                    id: missing.id,
                    reason: missing.reason,
                    tries: PATIENT_TRIES,
                })
            }
        }
    }
    // Present and goal position share the layout, so the bytes read are
    // valid goals as they are; decoding them checks that they are.
    for chunk in goals.chunks_exact(len) {
        pos.decode(chunk, series.byte_order())
            .map_err(BenchError::Position)?;
    }
    Ok(goals)
}

/// What the timed cycles measured.
struct Cycles {
    /// The cycles' periods.
    periods: Histogram,
    /// The same periods, in order.
    period_list: Vec<Duration>,
    /// Full cycles run.
    cycles: u64,
    /// Servos missing from a SYNC READ.
    missed: u64,
    /// From the start to the end of the last cycle.
    elapsed: Duration,
}

impl Cycles {
    /// Cycles per second achieved.
    fn achieved_rate_hz(&self) -> f64 {
        if self.elapsed.is_zero() {
            0.0
        } else {
            self.cycles as f64 / self.elapsed.as_secs_f64()
        }
    }

    /// Each cycle's period against the mean period.
    fn period_errors(&self) -> Histogram {
        let mean = if self.cycles == 0 {
            Duration::ZERO
        } else {
            self.elapsed / u32::try_from(self.cycles).unwrap_or(u32::MAX)
        };
        let mut errors = Histogram::new(Duration::from_millis(100));
        for p in &self.period_list {
            errors.record(p.abs_diff(mean));
        }
        errors
    }
}

/// Runs full cycles (a SYNC WRITE of `goals`, a SYNC READ of `pos`) on
/// `ids` for `duration`, timing each.
fn run_cycles<T: Transport>(
    servo_bus: &mut Bus<T>,
    bus: &BusConfig,
    ids: &[u8],
    goals: &[u8],
    pos: &Register,
    duration: Duration,
) -> Result<Cycles, BenchError> {
    let mut periods = Histogram::new(Duration::from_millis(100));
    let mut period_list = Vec::with_capacity(1 << 16);
    let start = servo_bus.clock().now();
    let end = start + duration;
    let mut last = start;
    let mut cycles = 0u64;
    let mut missed = 0u64;
    while servo_bus.clock().now() < end {
        servo_bus
            .sync_write(addr::GOAL_POSITION, ids, goals)
            .map_err(failed(bus, "SYNC WRITE"))?;
        let read = servo_bus
            .sync_read(pos.address, pos.size, ids)
            .map_err(failed(bus, "SYNC READ"))?;
        let missing = read.missing() as u64;
        missed += missing;
        if missing > 0 {
            // Let a late reply come before the next request (which would
            // talk over it): it counts as late, not lost.
            servo_bus
                .await_late_replies(LATE_REPLY_WAIT)
                .map_err(failed(bus, "waiting for late replies"))?;
        }
        let now = servo_bus.clock().now();
        let period = now - last;
        last = now;
        cycles += 1;
        periods.record(period);
        period_list.push(period);
    }
    Ok(Cycles {
        periods,
        period_list,
        cycles,
        missed,
        elapsed: last - start,
    })
}

/// Each servo's round trip, from the bus's counters.
fn servo_rtts<T: Transport>(servo_bus: &Bus<T>, bus: &BusConfig) -> Vec<ServoRtt> {
    bus.joints
        .iter()
        .map(|j| {
            let c = servo_bus.servo_counters(j.id);
            let us = |d: Option<Duration>| d.map_or(0.0, |d| d.as_secs_f64() * 1e6);
            ServoRtt {
                id: j.id,
                joint: j.name.clone(),
                replies: c.rtt.count,
                rtt_mean_us: us(c.rtt.mean()),
                rtt_max_us: us(c.rtt.max()),
                timeouts: c.timeouts,
            }
        })
        .collect()
}

/// Cycles whose period exceeded `planned`, the planned full cycle time.
pub fn overruns(periods: &[Duration], planned: Duration) -> u64 {
    periods.iter().filter(|p| **p > planned).count() as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_overrun_is_a_period_longer_than_the_planned_cycle() {
        let us = Duration::from_micros;
        let periods = [us(900), us(1180), us(1181), us(5000)];
        assert_eq!(overruns(&periods, us(1180)), 2);
        assert_eq!(overruns(&periods, us(5000)), 0);
        assert_eq!(overruns(&[], us(1)), 0);
    }
}
