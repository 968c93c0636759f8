//! Poses as a motion file writes them: `name: value` pairs kept in file
//! order, a keyframe's reference to a pose, and their check against the
//! robot's joints and limits.

use std::fmt;

use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};

use super::error::{ConfigError, Source};
use super::locate::FieldPath;
use super::robot::Robot;
use super::Units;

/// `name: value` pairs in file order (a map would lose the order, and errors
/// should name the first bad entry as written).
#[derive(Default)]
pub(super) struct PairList<T>(pub(super) Vec<(String, T)>);

pub(super) type PoseMap = PairList<f64>;
pub(super) type PoseList = PairList<PoseMap>;

impl<'de, T: Deserialize<'de>> Deserialize<'de> for PairList<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for V<T> {
            type Value = PairList<T>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a mapping of names to values")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let mut v: Vec<(String, T)> = Vec::new();
                while let Some(k) = map.next_key::<String>()? {
                    if v.iter().any(|(n, _)| *n == k) {
                        return Err(de::Error::custom(format!("`{k}` is given twice")));
                    }
                    v.push((k, map.next_value()?));
                }
                Ok(PairList(v))
            }
        }
        d.deserialize_map(V(std::marker::PhantomData))
    }
}

/// A keyframe's pose: a pose's name, or a map of joint positions.
pub(super) enum PoseRef {
    Name(String),
    Map(PoseMap),
}

impl<'de> Deserialize<'de> for PoseRef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = PoseRef;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a pose name or a map of joint positions")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<PoseRef, E> {
                Ok(PoseRef::Name(v.to_owned()))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<PoseRef, A::Error> {
                PoseMap::deserialize(de::value::MapAccessDeserializer::new(map)).map(PoseRef::Map)
            }
        }
        d.deserialize_any(V)
    }
}

pub(super) fn list(names: &[&str]) -> String {
    if names.is_empty() {
        "none defined".to_owned()
    } else {
        names.join(", ")
    }
}

pub(super) struct Resolver<'a> {
    pub(super) src: &'a Source,
    pub(super) robot: &'a Robot,
    pub(super) units: Units,
}

impl Resolver<'_> {
    /// Every joint named exists and every value is inside its joint's limits.
    pub(super) fn check_pose(
        &self,
        pose: &PoseMap,
        at: &FieldPath,
        keyframe: Option<usize>,
    ) -> Result<(), ConfigError> {
        let which = keyframe.map_or(String::new(), |k| format!("keyframe {k}: "));
        for (name, value) in &pose.0 {
            let field = at.key(name);
            let Some(joint) = self.robot.joint(name) else {
                let known: Vec<&str> = self.robot.joints().map(|j| j.name.as_str()).collect();
                return Err(self.src.key_error(
                    &field,
                    format!(
                        "{which}robot `{}` has no joint `{name}` (joints: {})",
                        self.robot.name,
                        list(&known)
                    ),
                ));
            };
            if !value.is_finite() {
                return Err(self.src.error(&field, "must be a finite number"));
            }
            let v = self.units.convert(*value, self.robot.units);
            // A hair of tolerance so a limit written in the other unit
            // (90 deg vs 1.5708 rad) still counts as inside.
            let tol = 1e-9 * (1.0 + v.abs());
            if v < joint.min - tol || v > joint.max + tol {
                let (min, max) = (
                    self.robot.units.convert(joint.min, self.units),
                    self.robot.units.convert(joint.max, self.units),
                );
                let [lo, hi] = super::limit_origins(joint, self.robot.units);
                let origin = if v < joint.min { lo } else { hi };
                return Err(self.src.error(
                    &field,
                    format!(
                        "{which}{value} {} is outside the limits of joint `{name}` \
                         [{}, {}] {} (the {} limit comes from {origin})",
                        self.units,
                        round(min),
                        round(max),
                        self.units,
                        if v < joint.min { "lower" } else { "upper" },
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// `x` to two decimals, as a limit is said in a message (a calibrated limit
/// is measured: 96.92578125 says nothing 96.93 does not).
fn round(x: f64) -> f64 {
    (x * 100.0).round() / 100.0
}
