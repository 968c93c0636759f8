//! The summary of a run, printed by `servobus play` (and as JSON with
//! `--json`).

use serde::Serialize;

use crate::fault::Fault;
use crate::target::LiveReport;
use crate::telemetry::Finish;

/// Three figures of a distribution (of period errors, latencies, ...), in
/// the unit the report gives them in (us, ms).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Quantiles {
    /// Median.
    pub p50: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Largest.
    pub max: f64,
}

impl Quantiles {
    /// The median, 99th percentile and largest of `histogram`, each
    /// duration given in units of `unit` (`Duration::from_micros(1)` for
    /// figures in us).
    pub fn of(histogram: &crate::stats::Histogram, unit: std::time::Duration) -> Quantiles {
        let per = unit.as_secs_f64();
        let f = |d: std::time::Duration| d.as_secs_f64() / per;
        Quantiles {
            p50: f(histogram.quantile(0.5)),
            p99: f(histogram.quantile(0.99)),
            max: f(histogram.max()),
        }
    }
}

/// One joint's tracking error over the run, in the report's units.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JointReport {
    /// The joint's name.
    pub name: String,
    /// Root mean square of `planned - measured` over every fresh reading.
    pub rms_error: f64,
    /// Largest absolute error.
    pub max_error: f64,
    /// Fresh readings counted.
    pub readings: u64,
    /// Goals clamped to the joint's limits.
    pub clamps: u64,
    /// Times it stalled in a live session and was held pressed with
    /// bounded effort ([`StallEvent`](crate::Telemetry::Stall)) instead of
    /// ending the run.
    pub stalls: u64,
    /// How long it was held so, s.
    pub stalled_s: f64,
    /// A wheel joint's largest |commanded speed|, units/s (`None`, and
    /// left out of the JSON, for a position joint). A wheel's error
    /// figures above stay 0: it is not tracked against the path.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_commanded_speed: Option<f64>,
    /// A wheel joint's largest |present speed| read, units/s (`None` for a
    /// position joint).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_measured_speed: Option<f64>,
}

/// One bus's figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BusReport {
    /// The bus's name.
    pub name: String,
    /// Cycles run.
    pub cycles: u64,
    /// Deadlines skipped because a cycle overran.
    pub overruns: u64,
    /// Mean fraction of the period the bus work took (measured).
    pub utilisation: f64,
    /// Largest fraction of the period one cycle took.
    pub peak_utilisation: f64,
    /// The fraction servobus-timing predicted for the full cycle.
    pub planned_utilisation: f64,
    /// Each servo is read once every this many cycles (round robin).
    pub read_every: usize,
    /// Replies that did not arrive in time (each attempt).
    pub timeouts: u64,
    /// Requests asked again.
    pub retries: u64,
    /// Servo readings missing after every retry.
    pub missed_replies: u64,
    /// The adapter latency was learned (`latency_us: auto`), not given.
    pub latency_learned: bool,
    /// Requests sent at start-up to measure the adapter (0: not measured).
    pub startup_probes: u32,
    /// How long that measurement took, ms.
    pub startup_probe_ms: f64,
    /// Mean lateness of the replies beyond the link model: the adapter's
    /// latency as measured, us.
    pub latency_us: f64,
    /// Its 99th percentile over the last reads, us.
    pub latency_p99_us: f64,
    /// The reply deadline in force at the end for a read of every servo, us.
    pub reply_deadline_us: f64,
    /// The robot file's EEPROM `servo:` settings its servos hold otherwise
    /// (a run writes no EEPROM: `servobus doctor --fix --write-servos`
    /// stores them), as read at start-up; left out of the JSON when none.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub eeprom_differences: Vec<SettingDifference>,
}

/// An EEPROM `servo:` setting of the robot file that a servo holds
/// otherwise.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SettingDifference {
    /// The joint.
    pub joint: String,
    /// Its servo's ID.
    pub id: u8,
    /// The `servo:` key (`p`, `max_temperature`, ...).
    pub setting: &'static str,
    /// The register.
    pub register: &'static str,
    /// What the servo holds, raw.
    pub held: i32,
    /// What the robot file asks, raw.
    pub wanted: i32,
}

/// The summary of a run. The first fields are those of
/// `servobus bench --json`; `joints` holds the tracking error per joint.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[non_exhaustive]
pub struct Report {
    /// Control cycles run (of the first bus; the buses run in step).
    pub cycles: u64,
    /// Cycles per second achieved: cycles after the first over the time
    /// between the first and the last cycle's start.
    pub achieved_rate_hz: f64,
    /// The requested rate.
    pub planned_rate_hz: f64,
    /// Deviation of each cycle's start interval from the period, us (every
    /// bus).
    pub period_error_us: Quantiles,
    /// Deadlines skipped because a cycle overran (every bus).
    pub overruns: u64,
    /// Replies that timed out (every attempt, every bus).
    pub timeouts: u64,
    /// Requests asked again (every bus).
    pub retries: u64,
    /// Servo readings missing after every retry (every bus).
    pub missed_replies: u64,
    /// Goals clamped to the joint limits (a clamp means the plan was wrong).
    pub clamps: u64,
    /// Telemetry messages dropped because the consumer was slow.
    pub telemetry_dropped: u64,
    /// Mean measured bus utilisation of the busiest bus.
    pub utilisation: f64,
    /// Time from the first to the last cycle, s.
    pub duration_s: f64,
    /// Start of the last cycle minus its deadline: drift of the loop, us.
    pub drift_us: f64,
    /// The lead in use at the end, ms.
    pub lead_ms: f64,
    /// Whether that lead was identified from the run's motion (`lead_ms:
    /// auto` and enough motion); false for a fixed lead or one still at
    /// its prior from the servos' response lag.
    pub lead_identified: bool,
    /// The angle unit of every joint figure.
    pub units: &'static str,
    /// Tracking error per joint, in the robot's joint order.
    pub joints: Vec<JointReport>,
    /// Per-bus figures.
    pub buses: Vec<BusReport>,
    /// Why the run ended.
    pub finish: Finish,
    /// The fault that ended it, if one did.
    pub fault: Option<Fault>,
    /// What the real-time set-up could not do (core pinning, SCHED_FIFO).
    pub warnings: Vec<String>,
    /// What happened to live targets, in a run that had any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub live: Option<LiveReport>,
}

impl Report {
    /// The largest RMS tracking error over the joints.
    pub fn worst_rms_error(&self) -> f64 {
        self.joints.iter().map(|j| j.rms_error).fold(0.0, f64::max)
    }

    /// The joints that stalled and were held in a live session.
    pub fn stalled_joints(&self) -> impl Iterator<Item = &JointReport> {
        self.joints.iter().filter(|j| j.stalls > 0)
    }

    /// The largest tracking error of any joint.
    pub fn worst_max_error(&self) -> f64 {
        self.joints.iter().map(|j| j.max_error).fold(0.0, f64::max)
    }
}
