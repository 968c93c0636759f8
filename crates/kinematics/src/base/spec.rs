//! The robot file's `base:` section as serde reads it.

use serde::Deserialize;

/// A robot file's `base:` section: the geometry of a wheeled base, one of
/// two kinds, written as a mapping with one key (`omni3:` or
/// `differential:`). Checked against the robot's joints by
/// [`Base::new`](crate::Base::new).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(try_from = "OneKind")]
pub enum BaseSpec {
    /// Three omni wheels around the centre (LeKiwi).
    Omni3(Omni3Spec),
    /// Two wheels on one axle, driven independently (XLeRobot).
    Differential(DifferentialSpec),
}

/// The section as written: a mapping whose one key is the kind. Read as a
/// struct rather than an externally tagged enum because serde_yaml reads
/// those from YAML tags (`!omni3`), not from a key.
#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a base: a mapping with one key, `omni3:` or `differential:`"
)]
struct OneKind {
    omni3: Option<Omni3Spec>,
    differential: Option<DifferentialSpec>,
}

impl TryFrom<OneKind> for BaseSpec {
    type Error = &'static str;

    fn try_from(raw: OneKind) -> Result<Self, Self::Error> {
        match (raw.omni3, raw.differential) {
            (Some(omni3), None) => Ok(BaseSpec::Omni3(omni3)),
            (None, Some(differential)) => Ok(BaseSpec::Differential(differential)),
            (Some(_), Some(_)) => Err("a base is one kind: `omni3:` or `differential:`, not both"),
            (None, None) => Err("a base needs its kind: `omni3:` or `differential:`"),
        }
    }
}

/// `base.omni3`: three omni wheels whose axles point at the centre.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "an omni3 base: a mapping with `wheel_radius_mm:`, `base_radius_mm:` and `wheels:`"
)]
pub struct Omni3Spec {
    /// The radius of every wheel, mm.
    pub wheel_radius_mm: f64,
    /// The distance from the base's centre to each wheel's contact, mm.
    pub base_radius_mm: f64,
    /// Exactly three wheels, in the order their speeds are given.
    pub wheels: Vec<OmniWheelSpec>,
}

/// One wheel of `base.omni3.wheels`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "an omni wheel: a mapping with `joint:` and `angle_deg:`"
)]
pub struct OmniWheelSpec {
    /// The joint (a servo in wheel mode) that drives the wheel.
    pub joint: String,
    /// Where the wheel sits around the centre, degrees from the base's +x
    /// (forward), counter-clockwise seen from above.
    pub angle_deg: f64,
}

/// `base.differential`: two wheels on one axle through the centre.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a differential base: a mapping with `wheel_radius_mm:`, `track_mm:`, `left:` and `right:`"
)]
pub struct DifferentialSpec {
    /// The radius of both wheels, mm.
    pub wheel_radius_mm: f64,
    /// The distance between the two wheels' contacts, mm.
    pub track_mm: f64,
    /// The joint that drives the left wheel (positive: forward).
    pub left: String,
    /// The joint that drives the right wheel (positive: forward).
    pub right: String,
}
