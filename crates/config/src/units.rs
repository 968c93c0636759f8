//! Angle units of robot and motion files.

use serde::Deserialize;

/// The unit of every angle in a file (velocities are units/s, and so on).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "lowercase")]
#[serde(expecting = "`deg` or `rad`")]
pub enum Units {
    /// Degrees (the default).
    #[default]
    #[serde(alias = "degrees", alias = "degree")]
    Deg,
    /// Radians.
    #[serde(alias = "radians", alias = "radian")]
    Rad,
}

impl Units {
    /// Radians per one of this unit.
    pub fn rad_per_unit(self) -> f64 {
        match self {
            Units::Deg => std::f64::consts::PI / 180.0,
            Units::Rad => 1.0,
        }
    }

    /// `value` in this unit, converted to radians.
    pub fn to_rad(self, value: f64) -> f64 {
        match self {
            Units::Deg => value.to_radians(),
            Units::Rad => value,
        }
    }

    /// `rad` radians, converted to this unit.
    pub fn from_rad(self, rad: f64) -> f64 {
        match self {
            Units::Deg => rad.to_degrees(),
            Units::Rad => rad,
        }
    }

    /// `value` in this unit, converted to `to`.
    pub fn convert(self, value: f64, to: Units) -> f64 {
        if self == to {
            value
        } else {
            to.from_rad(self.to_rad(value))
        }
    }

    /// The unit's short name as written in files (`deg`, `rad`).
    pub fn name(self) -> &'static str {
        match self {
            Units::Deg => "deg",
            Units::Rad => "rad",
        }
    }
}

impl std::fmt::Display for Units {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
