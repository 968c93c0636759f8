//! The cost of one control cycle: bytes, wire time and expected duration.

use core::time::Duration;

use servobus_protocol::{frame_len, MAX_PARAMS};

use crate::{sync_write_bytes, sync_write_frames, Block, Link};

/// The most servos one SYNC READ request can list (its length byte is
/// N + 4 <= 255).
pub const MAX_SYNC_READ_SERVOS: usize = MAX_PARAMS - 2;

/// One servo on a bus, as far as timing is concerned.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Servo {
    /// Its ID (0..=253).
    pub id: u8,
    /// Its return delay (register 7): the wait before it starts a reply.
    pub return_delay: Duration,
    /// Whether it answers SYNC READ (STS/SMS series do; SCS series do not
    /// and are read with one READ each).
    pub sync_read: bool,
}

impl Servo {
    /// A servo with the given ID, return delay and SYNC READ support (take
    /// the last from the series of its model).
    pub const fn new(id: u8, return_delay: Duration, sync_read: bool) -> Servo {
        Servo {
            id,
            return_delay,
            sync_read,
        }
    }

    /// An STS/SMS servo (answers SYNC READ).
    pub const fn sts(id: u8, return_delay: Duration) -> Servo {
        Servo::new(id, return_delay, true)
    }

    /// An SCS servo (no SYNC READ: read with one READ each).
    pub const fn scs(id: u8, return_delay: Duration) -> Servo {
        Servo::new(id, return_delay, false)
    }
}

/// What one control cycle costs on the bus.
///
/// A cycle is the SYNC WRITE frame(s) of the goals, then the feedback: one
/// SYNC READ for the servos that support it and one READ for each that does
/// not. The expected duration is the wire time of every byte both ways, plus
/// each reply's return delay and turnaround, plus the adapter's latency and
/// the link's overhead once per round trip (a request whose reply the host
/// waits for), plus the link's reply overhead once per reply. Write-only
/// frames cost their wire time alone: nothing waits for them, so the adapter
/// sends them back to back with the request that follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CycleCost {
    /// Bytes on the wire per cycle, both directions.
    pub bytes: usize,
    /// Wire time of those bytes (10 bits each at the baud rate).
    pub wire_time: Duration,
    /// Expected duration of the cycle: wire time + return delays +
    /// turnarounds + the link's cost of its exchanges (one adapter latency
    /// and one overhead per round trip, one reply overhead per reply:
    /// [`Link::exchange_cost`]).
    pub cycle_time: Duration,
    /// SYNC WRITE frames per cycle.
    pub write_frames: usize,
    /// Requests per cycle that wait for replies (SYNC READs and READs).
    pub round_trips: usize,
    /// Servos read back in this cycle.
    pub servos_read: usize,
}

impl CycleCost {
    /// Wire time in microseconds.
    pub fn wire_time_us(&self) -> f64 {
        micros(self.wire_time)
    }

    /// Expected cycle time in microseconds.
    pub fn cycle_time_us(&self) -> f64 {
        micros(self.cycle_time)
    }

    /// The highest rate at which cycles can follow one another:
    /// 1 / cycle time (infinite for an empty cycle).
    pub fn max_rate_hz(&self) -> f64 {
        rate_of(self.cycle_time)
    }

    /// The fastest rate to offer people: [`max_rate_hz`](Self::max_rate_hz)
    /// floored by [`floor_rate_hz`]. Every command that names a maximum
    /// rate names this one, so they all agree.
    pub fn fastest_rate_hz(&self) -> f64 {
        floor_rate_hz(self.max_rate_hz())
    }

    /// The highest rate the wire alone allows, with no return delay, turnaround
    /// or latency: 1 / wire time.
    pub fn wire_limited_rate_hz(&self) -> f64 {
        rate_of(self.wire_time)
    }

    /// The fraction of each period at `rate_hz` that the cycle takes (above
    /// 1.0: the rate cannot be met).
    pub fn utilisation(&self, rate_hz: f64) -> f64 {
        self.cycle_time.as_secs_f64() * rate_hz
    }

    /// Whether the cycle fits in one period at `rate_hz`.
    pub fn fits(&self, rate_hz: f64) -> bool {
        self.utilisation(rate_hz) <= 1.0
    }
}

fn micros(d: Duration) -> f64 {
    d.as_nanos() as f64 / 1_000.0
}

/// A maximum rate rounded the one way that keeps it a maximum: down to a
/// whole hertz (the exact figure below 1 Hz, where flooring would give 0).
/// Infinite and NaN rates come back unchanged.
///
/// ```
/// use servobus_timing::floor_rate_hz;
/// assert_eq!(floor_rate_hz(598.9), 598.0);
/// assert_eq!(floor_rate_hz(0.25), 0.25);
/// ```
pub fn floor_rate_hz(max_hz: f64) -> f64 {
    if max_hz.is_finite() && max_hz >= 1.0 {
        max_hz.floor()
    } else {
        max_hz
    }
}

fn rate_of(d: Duration) -> f64 {
    if d.is_zero() {
        f64::INFINITY
    } else {
        1.0 / d.as_secs_f64()
    }
}

pub(crate) fn nanos(d: Duration) -> u64 {
    u64::try_from(d.as_nanos()).unwrap_or(u64::MAX)
}

/// What varies between the cycles the planner compares.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CycleSpec {
    pub link: Link,
    /// Servos written each cycle (all of them).
    pub written: usize,
    pub write: Option<Block>,
    /// Bytes read from each servo read back (None: no feedback).
    pub read_len: Option<u8>,
    /// Count every return delay as 0 (the "return delay 0" fix).
    pub zero_return_delay: bool,
}

impl CycleSpec {
    /// The cost of a cycle that writes every servo and reads back `readers`.
    pub fn cost(&self, readers: &[Servo]) -> CycleCost {
        let mut bytes = 0usize;
        let mut write_frames = 0;
        if let Some(w) = self.write {
            bytes += sync_write_bytes(self.written, w.len);
            write_frames = sync_write_frames(self.written, w.len);
        }
        let mut waits = 0u64;
        let mut round_trips = 0usize;
        let mut servos_read = 0usize;
        if let Some(len) = self.read_len {
            let reply = frame_len(usize::from(len));
            let turnaround = nanos(self.link.turnaround);
            let mut synced = 0usize;
            for s in readers {
                let delay = if self.zero_return_delay {
                    0
                } else {
                    nanos(s.return_delay)
                };
                waits = waits.saturating_add(delay.saturating_add(turnaround));
                if s.sync_read {
                    // Its ID in the SYNC READ request, then its reply.
                    synced += 1;
                    bytes += 1 + reply;
                } else {
                    bytes += frame_len(2) + reply;
                    round_trips += 1;
                }
            }
            if synced > 0 {
                // Requests beyond 251 IDs are split, each its own round trip.
                let requests = synced.div_ceil(MAX_SYNC_READ_SERVOS);
                bytes += requests * frame_len(2);
                round_trips += requests;
            }
            servos_read = readers.len();
        }
        let wire = self.link.wire_nanos(bytes);
        let link = nanos(self.link.exchange_cost(round_trips, servos_read));
        let cycle = wire.saturating_add(waits).saturating_add(link);
        CycleCost {
            bytes,
            wire_time: Duration::from_nanos(wire),
            cycle_time: Duration::from_nanos(cycle),
            write_frames,
            round_trips,
            servos_read,
        }
    }
}
