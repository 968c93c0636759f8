//! The shape of a robot file as serde reads it, before validation.

use std::collections::HashMap;
use std::path::PathBuf;

use std::fmt;

use serde::de::{self, Visitor};
use serde::{Deserialize, Deserializer};

use super::faults::RawFaults;
use super::JointMode;
use crate::Units;

/// A robot file, field for field ([`Robot`](super::Robot) says what each
/// means); absent optional fields take their defaults here.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(
    expecting = "a robot file: a mapping with `name:`, `buses:` and optional `units:`, `rate:`, ..."
)]
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
    pub kinematics: Option<super::urdf::RawKinematics>,
    #[serde(default)]
    pub base: Option<servobus_kinematics::BaseSpec>,
    /// `servo:` settings per servo model, for every joint of that model
    /// (a joint's own `servo:` keys win).
    #[serde(default)]
    pub servo_defaults: std::collections::BTreeMap<String, RawServo>,
}

fn default_rate() -> f64 {
    100.0
}

/// `latency_us`: a number of microseconds, or `auto`.
#[derive(Default)]
pub(super) enum LatencySpec {
    Micros(u64),
    #[default]
    Auto,
    Word(String),
}

impl<'de> Deserialize<'de> for LatencySpec {
    // By hand rather than `untagged`: serde's untagged enums lose the
    // position of the value and say `untagged enum LatencySpec`.
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = LatencySpec;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number of microseconds or `auto`")
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<LatencySpec, E> {
                Ok(LatencySpec::Micros(v))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<LatencySpec, E> {
                Ok(LatencySpec::Word(v.to_owned()))
            }
        }
        d.deserialize_any(V)
    }
}

fn default_baud() -> u32 {
    1_000_000
}

/// One entry of `buses` ([`BusConfig`](super::BusConfig)).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(expecting = "a bus: a mapping with `name:`, `joints:` and optional `baud:`, `port:`, ...")]
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
/// `min` and `max` are optional here because a wheel has neither; a
/// position joint without them is refused in validation, naming it.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(
    expecting = "a joint: a mapping with `name:`, `id:`, `model:`, `min:`, `max:` (not for `mode: wheel`), `max_velocity:`, `max_acceleration:`, ..."
)]
pub(super) struct RawJoint {
    pub name: String,
    pub id: i64,
    pub model: String,
    #[serde(default)]
    pub mode: JointMode,
    #[serde(default)]
    pub min: Option<f64>,
    #[serde(default)]
    pub max: Option<f64>,
    pub max_velocity: f64,
    pub max_acceleration: f64,
    #[serde(default)]
    pub max_jerk: Option<f64>,
    #[serde(default)]
    pub offset: Option<f64>,
    #[serde(default)]
    pub inverted: bool,
    #[serde(default)]
    pub home: Option<f64>,
    #[serde(default)]
    pub servo: Option<RawServo>,
    #[serde(default)]
    pub faults: Option<RawFaults>,
}

/// A joint's `servo:` ([`ServoSettings`](super::ServoSettings)), the values
/// as written: wide types, so that an out-of-range gain or a negative
/// current is refused in validation with the accepted range.
#[derive(Deserialize, Clone, Default)]
#[serde(deny_unknown_fields)]
#[serde(
    expecting = "servo settings: a mapping with any of `p:`, `d:`, `i:`, `torque_limit:`, `protection_current:`, `acceleration:`, `max_temperature:`"
)]
pub(super) struct RawServo {
    #[serde(default)]
    pub p: Option<i64>,
    #[serde(default)]
    pub d: Option<i64>,
    #[serde(default)]
    pub i: Option<i64>,
    #[serde(default)]
    pub torque_limit: Option<f64>,
    #[serde(default)]
    pub protection_current: Option<f64>,
    #[serde(default)]
    pub acceleration: Option<f64>,
    #[serde(default)]
    pub max_temperature: Option<i64>,
}

impl RawServo {
    /// These settings, each one not given taken from `defaults`.
    pub fn or(&self, defaults: &RawServo) -> RawServo {
        RawServo {
            p: self.p.or(defaults.p),
            d: self.d.or(defaults.d),
            i: self.i.or(defaults.i),
            torque_limit: self.torque_limit.or(defaults.torque_limit),
            protection_current: self.protection_current.or(defaults.protection_current),
            acceleration: self.acceleration.or(defaults.acceleration),
            max_temperature: self.max_temperature.or(defaults.max_temperature),
        }
    }
}
