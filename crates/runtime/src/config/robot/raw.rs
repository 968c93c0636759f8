//! The shape of a robot file as serde reads it, before validation.

use std::collections::HashMap;
use std::path::PathBuf;

use serde::Deserialize;

use crate::config::Units;

/// A robot file, field for field ([`Robot`](super::Robot) says what each
/// means); absent optional fields take their defaults here.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRobot {
    pub name: String,
    #[serde(default)]
    pub units: Units,
    #[serde(default = "default_rate")]
    pub rate: f64,
    #[serde(default)]
    pub lead_ms: Option<f64>,
    #[serde(default)]
    pub calibration: Option<PathBuf>,
    #[serde(default)]
    pub calibration_pose: HashMap<String, f64>,
    pub buses: Vec<RawBus>,
    #[serde(default)]
    pub kinematics: Option<servobus_kinematics::Spec>,
}

fn default_rate() -> f64 {
    100.0
}

/// `latency_us`: a number of microseconds, or `auto`.
#[derive(Deserialize, Default)]
#[serde(untagged)]
pub(super) enum LatencySpec {
    Micros(u64),
    #[default]
    #[serde(skip)]
    Auto,
    Word(String),
}

fn default_baud() -> u32 {
    1_000_000
}

/// One entry of `buses` ([`BusConfig`](super::BusConfig)).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBus {
    pub name: String,
    #[serde(default)]
    pub port: Option<String>,
    #[serde(default = "default_baud")]
    pub baud: u32,
    #[serde(default)]
    pub latency_us: LatencySpec,
    #[serde(default)]
    pub return_delay_us: u64,
    #[serde(default)]
    pub busy_poll: bool,
    #[serde(default)]
    pub round_robin: bool,
    pub joints: Vec<RawJoint>,
}

/// One entry of a bus's `joints` ([`JointConfig`](super::JointConfig)).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawJoint {
    pub name: String,
    pub id: i64,
    pub model: String,
    pub min: f64,
    pub max: f64,
    pub max_velocity: f64,
    pub max_acceleration: f64,
    #[serde(default)]
    pub max_jerk: Option<f64>,
    #[serde(default)]
    pub offset: f64,
    #[serde(default)]
    pub inverted: bool,
    #[serde(default)]
    pub home: Option<f64>,
}
