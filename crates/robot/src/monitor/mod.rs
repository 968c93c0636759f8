//! The monitor's sampler: what every servo of a bus is doing, refreshed
//! live (`servobus monitor` renders it).
//!
//! A [`Poller`] reads one register block (torque enable 40 to the moving
//! flag 66, on STS/SMS servos on to the present current at 69) from every
//! servo with one SYNC READ per refresh (SCS servos, which lack SYNC READ,
//! are read one after another by the driver), and
//! keeps a [`Row`] per servo: a servo that does not answer is marked
//! missing and keeps its last values, so the others go on updating.
//! [`Frame`] is one refresh of every row with the bus summary, for a
//! program to show (the command line: as a table, or as one JSON line).
//! `servobus play --monitor` builds the same frames from the runtime's
//! telemetry ([`TelemetryRows`]).

mod current;
mod telemetry;

use std::collections::VecDeque;
use std::time::Duration;

use serde::Serialize;
use servobus_config::{BusConfig, JointMap, Units};
use servobus_driver::{Bus, BusError, Clock, Transport};
use servobus_protocol::registers::{addr, model_by_number, Model, Series};
use servobus_protocol::StatusFlags;

pub use current::{block_len, milliamps_per_count};
pub use telemetry::TelemetryRows;

/// First address of the block read every refresh (torque enable).
pub const BLOCK_START: u8 = addr::TORQUE_ENABLE;
/// Bytes of the block every series has: torque enable (40) to the moving
/// flag (66). STS/SMS servos are read further, to their present current
/// ([`block_len`]).
pub const BLOCK_LEN: u8 = addr::MOVING - addr::TORQUE_ENABLE + 1;
/// Reply latencies kept per servo for the p99.
const LATENCY_WINDOW: usize = 512;
/// The span the read rate and the bus utilisation are averaged over.
const RATE_WINDOW: Duration = Duration::from_secs(1);

/// The names of the flags set in `flags` (the protocol's names,
/// [`StatusFlags::NAMES`], in their order).
pub fn flag_names(flags: StatusFlags) -> Vec<&'static str> {
    StatusFlags::NAMES
        .iter()
        .filter(|(bit, _)| flags.contains(*bit))
        .map(|(_, name)| *name)
        .collect()
}

/// One servo as last seen.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Row {
    /// Its ID.
    pub id: u8,
    /// The joint it drives, when the robot file names it.
    pub joint: Option<String>,
    /// The model's name.
    pub model: String,
    /// Whether it answered the last read.
    pub present: bool,
    /// Why not, when it did not.
    pub missing: Option<String>,
    /// Position in degrees: the joint's angle when the joint is known, else
    /// the servo's from its mid-travel.
    pub position_deg: Option<f64>,
    /// Position in ticks.
    pub position_ticks: Option<i32>,
    /// Goal position in degrees (as the position).
    pub goal_deg: Option<f64>,
    /// Goal position in ticks.
    pub goal_ticks: Option<i32>,
    /// Speed, degrees per second.
    pub speed_deg_s: Option<f64>,
    /// Load, percent of the maximum torque (signed).
    pub load_pct: Option<f64>,
    /// Motor current, mA (signed): STS/SMS servos' `present_current` in
    /// the register's unit (6.5 mA a count); `None` for SCS servos, which
    /// have no documented current register.
    pub current_ma: Option<f64>,
    /// Supply voltage, V.
    pub voltage_v: Option<f64>,
    /// Temperature, C.
    pub temperature_c: Option<f64>,
    /// Torque on.
    pub torque: Option<bool>,
    /// The status flags set, by name.
    pub flags: Vec<&'static str>,
    /// Replies received.
    pub replies: u64,
    /// Reads it did not answer.
    pub timeouts: u64,
    /// Reads in a row it has not answered (0 when it answered the last).
    pub missed_in_row: u32,
    /// 99th percentile of its reply latency (request sent to its reply
    /// received), microseconds. With one SYNC READ the servos answer in
    /// turn, so it grows along the bus: a later servo waits for the earlier
    /// ones' replies, not for itself.
    pub p99_latency_us: Option<f64>,
}

/// Reads in a row a servo must miss before it counts as missing: one late
/// reply (a busy host, a noisy line) is counted, not flagged. A servo that
/// has never answered is missing at once (the first read already asked it
/// patiently, several times).
pub const MISSING_AFTER: u32 = 3;

impl Row {
    /// Whether the servo counts as missing: it did not answer the last
    /// read, and either has never answered or has now missed
    /// [`MISSING_AFTER`] reads in a row.
    pub fn is_missing(&self) -> bool {
        !self.present && (self.missed_in_row >= MISSING_AFTER || self.position_ticks.is_none())
    }

    fn empty(id: u8, joint: Option<String>, model: String) -> Row {
        Row {
            id,
            joint,
            model,
            present: false,
            missing: Some("not read yet".into()),
            position_deg: None,
            position_ticks: None,
            goal_deg: None,
            goal_ticks: None,
            speed_deg_s: None,
            load_pct: None,
            current_ma: None,
            voltage_v: None,
            temperature_c: None,
            torque: None,
            flags: Vec::new(),
            replies: 0,
            timeouts: 0,
            missed_in_row: 0,
            p99_latency_us: None,
        }
    }
}

/// One refresh: every row and the bus summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Frame {
    /// Seconds since the monitor started.
    pub time_s: f64,
    /// Where the figures come from: `bus` (read by the monitor) or
    /// `telemetry` (a running motion's).
    pub source: &'static str,
    /// Reads of every servo per second, over the last second.
    pub read_rate_hz: f64,
    /// Share of the last second the wire was busy with the monitor's
    /// requests and replies (or the runtime's cycle).
    pub utilisation: f64,
    /// One row per servo.
    pub servos: Vec<Row>,
    /// The last thing the user asked for, e.g. `torque off sent`.
    pub note: Option<String>,
}

impl Frame {
    /// Whether a servo is missing ([`Row::is_missing`]: one late reply is
    /// not) or reports a status flag (overheat, overload, ...): a problem
    /// found, for the exit code.
    pub fn has_problem(&self) -> bool {
        self.servos
            .iter()
            .any(|r| r.is_missing() || !r.flags.is_empty())
    }
}

/// One servo to watch.
#[derive(Debug, Clone)]
pub struct Watched {
    /// Its ID.
    pub id: u8,
    /// The joint, when known.
    pub joint: Option<String>,
    /// The model.
    pub model: &'static Model,
    /// Joint angle <-> ticks, when the joint is known.
    pub map: Option<JointMap>,
}

impl Watched {
    /// The servos of `bus` in the robot file.
    pub fn of_bus(bus: &BusConfig, units: Units) -> Vec<Watched> {
        bus.joints
            .iter()
            .map(|j| Watched {
                id: j.id,
                joint: Some(j.name.clone()),
                model: j.model,
                map: Some(JointMap::new(j, units)),
            })
            .collect()
    }

    /// Degrees of a position in ticks.
    pub fn degrees(&self, ticks: i32) -> f64 {
        match &self.map {
            Some(map) => map.from_ticks(ticks).to_degrees(),
            None => f64::from(ticks - self.model.resolution as i32 / 2) * self.model.deg_per_tick(),
        }
    }
}

/// Reads the block of every watched servo once per [`Poller::poll`].
#[derive(Debug)]
pub struct Poller {
    servos: Vec<Watched>,
    ids: Vec<u8>,
    rows: Vec<Row>,
    /// Per servo: replies counted by the driver and their total latency,
    /// at the last refresh.
    seen: Vec<(u64, f64)>,
    latencies: Vec<VecDeque<f64>>,
    /// (time, wire time) of each recent refresh.
    recent: VecDeque<(Duration, Duration)>,
    started: Option<Duration>,
    series: Series,
    /// Bytes read from each servo every refresh ([`block_len`]).
    block_len: u8,
}

impl Poller {
    /// A poller of `servos` (all of one series).
    pub fn new(servos: Vec<Watched>) -> Poller {
        let series = servos.first().map_or(Series::Sts, |s| s.model.series);
        let rows = servos
            .iter()
            .map(|s| Row::empty(s.id, s.joint.clone(), s.model.name.to_string()))
            .collect();
        Poller {
            ids: servos.iter().map(|s| s.id).collect(),
            seen: vec![(0, 0.0); servos.len()],
            latencies: vec![VecDeque::new(); servos.len()],
            servos,
            rows,
            recent: VecDeque::new(),
            started: None,
            series,
            block_len: block_len(series),
        }
    }

    /// The servos found on a bus by PING, identified by their model number
    /// (unknown models are left out).
    ///
    /// # Errors
    /// Only a transport failure.
    pub fn scan<T: Transport>(bus: &mut Bus<T>) -> Result<Vec<Watched>, BusError> {
        let saved = *bus.settings();
        bus.set_settings(saved.with_retries(0));
        let mut found = Vec::new();
        for id in 0..=servobus_protocol::MAX_ID {
            // A READ, not a PING: a PING's reply carrying the voltage flag
            // is byte for byte the PING and is skipped as its echo.
            let mut number = [0u8; 2];
            match bus.read(id, addr::MODEL_NUMBER, &mut number) {
                Ok(_) => {}
                Err(BusError::Transport(e)) => {
                    bus.set_settings(saved);
                    return Err(BusError::Transport(e));
                }
                Err(_) => continue,
            }
            let model = model_by_number(u16::from_le_bytes(number))
                .or_else(|| model_by_number(u16::from_be_bytes(number)));
            if let Some(model) = model {
                found.push(Watched {
                    id,
                    joint: None,
                    model,
                    map: None,
                });
            }
        }
        bus.set_settings(saved);
        Ok(found)
    }

    /// The IDs watched.
    pub fn ids(&self) -> &[u8] {
        &self.ids
    }

    /// One refresh: one SYNC READ of the series' block ([`block_len`])
    /// from every servo.
    ///
    /// # Errors
    /// Only for the read as a whole (the transport failed); missing servos
    /// are shown as missing.
    pub fn poll<T: Transport>(&mut self, bus: &mut Bus<T>) -> Result<(), BusError> {
        let first = self.started.is_none();
        self.started.get_or_insert(bus.clock().now());
        // The first read is patient (longer deadlines, the missing asked
        // again): a port just opened, or a simulator just started, may be
        // slow to answer, and a present servo must not look absent.
        let read = if first {
            bus.sync_read_patiently(BLOCK_START, self.block_len, &self.ids)?
        } else {
            bus.sync_read(BLOCK_START, self.block_len, &self.ids)?
        };
        let map = self.series.map();
        let ma_per_count = map.get("present_current").and_then(milliamps_per_count);
        let order = self.series.byte_order();
        let value = |data: &[u8], name: &str| -> Option<i32> {
            let reg = map.get(name)?;
            let at = usize::from(reg.address.checked_sub(BLOCK_START)?);
            reg.decode(data.get(at..at + usize::from(reg.size))?, order)
                .ok()
        };
        let mut answered = 0;
        for (i, result) in read.iter().enumerate() {
            let (Some(row), Some(w)) = (self.rows.get_mut(i), self.servos.get(i)) else {
                continue;
            };
            match result {
                Ok(reply) => {
                    answered += 1;
                    let d = reply.data;
                    let pos = value(d, "present_position");
                    let goal = value(d, "goal_position");
                    let per_tick = w.model.deg_per_tick();
                    row.present = true;
                    row.missing = None;
                    row.position_ticks = pos;
                    row.position_deg = pos.map(|t| w.degrees(t));
                    row.goal_ticks = goal;
                    row.goal_deg = goal.map(|t| w.degrees(t));
                    row.speed_deg_s = value(d, "present_speed").map(|v| f64::from(v) * per_tick);
                    row.load_pct = value(d, "present_load").map(|v| f64::from(v) / 10.0);
                    row.current_ma = ma_per_count
                        .and_then(|ma| Some(f64::from(value(d, "present_current")?) * ma));
                    row.voltage_v = value(d, "present_voltage").map(|v| f64::from(v) / 10.0);
                    row.temperature_c = value(d, "present_temperature").map(f64::from);
                    row.torque = value(d, "torque_enable").map(|v| v != 0);
                    row.flags = flag_names(reply.flags);
                    row.replies += 1;
                    row.missed_in_row = 0;
                }
                Err(m) => {
                    row.present = false;
                    row.missing = Some(m.reason.to_string());
                    row.timeouts += 1;
                    row.missed_in_row += 1;
                }
            }
        }
        self.record_latencies(bus, !first);
        let now = bus.clock().now();
        let link = bus.link();
        let (request, reply) = (8 + self.ids.len(), 6 + usize::from(self.block_len));
        let bytes = match self.series {
            Series::Sts => request + answered * reply,
            // One READ request of 8 bytes per servo.
            Series::Scs => 8 * self.ids.len() + answered * reply,
        };
        self.recent.push_back((now, link.wire_time(bytes)));
        while self
            .recent
            .front()
            .is_some_and(|(t, _)| now.saturating_sub(*t) > RATE_WINDOW)
        {
            self.recent.pop_front();
        }
        Ok(())
    }

    /// Takes each servo's new reply latencies from the driver's counters
    /// (their count and mean give the sum; the difference since the last
    /// refresh is the new replies' total).
    /// `keep`: false for the patient first read, whose waits are not the
    /// bus's usual latency.
    fn record_latencies<T: Transport>(&mut self, bus: &Bus<T>, keep: bool) {
        for (i, &id) in self.ids.iter().enumerate() {
            let rtt = &bus.servo_counters(id).rtt;
            let total = rtt.mean().map_or(0.0, |m| m.as_secs_f64() * 1e6) * rtt.count as f64;
            let (count0, total0) = self.seen[i];
            if keep && rtt.count > count0 {
                let n = rtt.count - count0;
                let each = (total - total0) / n as f64;
                let ring = &mut self.latencies[i];
                for _ in 0..n.min(LATENCY_WINDOW as u64) {
                    if ring.len() == LATENCY_WINDOW {
                        ring.pop_front();
                    }
                    ring.push_back(each.max(0.0));
                }
            }
            self.seen[i] = (rtt.count, total);
            self.rows[i].p99_latency_us = p99(&self.latencies[i]);
        }
    }

    /// The current frame.
    pub fn frame<C: Clock>(&self, clock: &C, note: Option<String>) -> Frame {
        let now = clock.now();
        let span = match (self.recent.front(), self.recent.back()) {
            (Some(a), Some(b)) if b.0 > a.0 => b.0 - a.0,
            _ => Duration::ZERO,
        };
        let (rate, util) = if span.is_zero() {
            (0.0, 0.0)
        } else {
            let n = (self.recent.len() - 1) as f64;
            let wire: Duration = self.recent.iter().skip(1).map(|r| r.1).sum();
            (
                n / span.as_secs_f64(),
                wire.as_secs_f64() / span.as_secs_f64(),
            )
        };
        Frame {
            time_s: now
                .saturating_sub(self.started.unwrap_or(now))
                .as_secs_f64(),
            source: "bus",
            read_rate_hz: rate,
            utilisation: util,
            servos: self.rows.clone(),
            note,
        }
    }
}

/// Turns the torque off on every servo of `ids` at once, with one SYNC
/// WRITE (a broadcast nobody answers).
///
/// # Errors
/// The driver's, when the frame cannot be sent.
pub fn torque_off<T: Transport>(bus: &mut Bus<T>, ids: &[u8]) -> Result<(), BusError> {
    let zeros = vec![0u8; ids.len()];
    bus.sync_write(addr::TORQUE_ENABLE, ids, &zeros)
}

/// The 99th percentile of `samples` (the runtime's one definition).
fn p99(samples: &VecDeque<f64>) -> Option<f64> {
    let mut v: Vec<f64> = samples.iter().copied().collect();
    servobus_runtime::stats::p99(&mut v, f64::total_cmp)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A servo that has answered before and now misses reads in a row.
    fn missed(reads: u32) -> Row {
        let mut r = Row::empty(2, Some("shoulder_lift".into()), "STS3215".into());
        r.position_ticks = Some(2048);
        r.replies = 10;
        r.present = reads == 0;
        r.missed_in_row = reads;
        r
    }

    fn frame(row: Row) -> Frame {
        Frame {
            time_s: 1.0,
            source: "bus",
            read_rate_hz: 20.0,
            utilisation: 0.1,
            servos: vec![row],
            note: None,
        }
    }

    #[test]
    fn one_late_reply_is_counted_not_a_missing_servo() {
        assert!(!missed(0).is_missing());
        for late in 1..MISSING_AFTER {
            assert!(!missed(late).is_missing(), "{late}");
            assert!(!frame(missed(late)).has_problem(), "{late}");
        }
        assert!(missed(MISSING_AFTER).is_missing());
        assert!(frame(missed(MISSING_AFTER)).has_problem());
    }

    #[test]
    fn a_servo_that_never_answered_is_missing_at_once() {
        let mut never = Row::empty(5, None, "STS3215".into());
        never.missed_in_row = 1;
        assert!(never.is_missing());
        assert!(frame(never).has_problem());
    }
}
