//! The monitor's rows built from a running motion's telemetry
//! (`servobus play --monitor`): no request of its own goes on the bus.
//!
//! The runtime reads positions (and with them each reply's status flags)
//! only, so load, current, voltage, temperature and reply latency stay
//! empty here; the monitor shows them as `-`.

use std::collections::VecDeque;

use servobus_config::{Robot, Units};
use servobus_runtime::CycleSample;

use super::{flag_names, Frame, Row, Watched};

/// The span the cycle rate is averaged over, s.
const RATE_WINDOW_S: f64 = 1.0;

/// Rows of every joint of a robot, kept up to date from cycle samples.
#[derive(Debug)]
pub struct TelemetryRows {
    servos: Vec<Watched>,
    rows: Vec<Row>,
    units: Units,
    /// Per joint: the age of the reading last seen, to count new ones.
    ages: Vec<f64>,
    misses: Vec<u32>,
    /// (time, busy share) of recent cycles of the first bus.
    recent: VecDeque<(f64, f64)>,
    period_s: f64,
    time_s: f64,
}

impl TelemetryRows {
    /// Rows for every joint of `robot`; samples carry angles in `units`,
    /// one cycle every `period_s` seconds.
    pub fn new(robot: &Robot, units: Units, period_s: f64) -> TelemetryRows {
        let servos: Vec<Watched> = robot
            .buses
            .iter()
            .flat_map(|b| Watched::of_bus(b, robot.units))
            .collect();
        let rows = servos
            .iter()
            .map(|s| Row::empty(s.id, s.joint.clone(), s.model.name.to_string()))
            .collect();
        TelemetryRows {
            ages: vec![f64::INFINITY; servos.len()],
            misses: vec![0; servos.len()],
            servos,
            rows,
            units,
            recent: VecDeque::new(),
            period_s,
            time_s: 0.0,
        }
    }

    /// Takes one cycle's sample in.
    pub fn record(&mut self, sample: &CycleSample) {
        for j in sample.joints() {
            let (Some(row), Some(w)) = (self.rows.get_mut(j.joint), self.servos.get(j.joint))
            else {
                continue;
            };
            let Some(map) = &w.map else { continue };
            let to_ticks = |v: f64| map.to_ticks(self.units.to_rad(v));
            let degrees = |v: f64| self.units.to_rad(v).to_degrees();
            row.goal_ticks = Some(to_ticks(j.commanded));
            row.goal_deg = Some(degrees(j.commanded));
            row.torque = Some(true);
            if let Some(m) = j.measured {
                row.position_ticks = Some(to_ticks(m));
                row.position_deg = Some(degrees(m));
                row.speed_deg_s = Some(degrees(j.velocity));
            }
            row.flags = flag_names(j.flags);
            row.present = j.missing_reads == 0 && j.measured.is_some();
            row.missed_in_row = if j.measured.is_some() {
                j.missing_reads
            } else {
                j.missing_reads.max(1)
            };
            row.missing = (!row.present).then(|| "no reply".to_string());
            let age = j.feedback_age.as_secs_f64();
            if row.present && age < self.ages[j.joint] {
                row.replies += 1;
            }
            self.ages[j.joint] = age;
            if j.missing_reads > self.misses[j.joint] {
                row.timeouts += 1;
            }
            self.misses[j.joint] = j.missing_reads;
        }
        if sample.bus == 0 {
            self.time_s = sample.time_s;
            let busy = sample.busy.as_secs_f64() / self.period_s.max(f64::EPSILON);
            self.recent.push_back((sample.time_s, busy));
            while self
                .recent
                .front()
                .is_some_and(|(t, _)| sample.time_s - t > RATE_WINDOW_S)
            {
                self.recent.pop_front();
            }
        }
    }

    /// The current frame.
    pub fn frame(&self, note: Option<String>) -> Frame {
        let (rate, util) = match (self.recent.front(), self.recent.back()) {
            (Some(a), Some(b)) if b.0 > a.0 => {
                let n = (self.recent.len() - 1) as f64;
                let busy = self.recent.iter().map(|r| r.1).sum::<f64>() / self.recent.len() as f64;
                (n / (b.0 - a.0), busy.min(1.0))
            }
            _ => (0.0, 0.0),
        };
        Frame {
            time_s: self.time_s,
            source: "telemetry",
            read_rate_hz: rate,
            utilisation: util,
            servos: self.rows.clone(),
            note,
        }
    }
}
