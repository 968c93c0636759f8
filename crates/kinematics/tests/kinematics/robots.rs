//! The shipped robot files' geometry, read straight from the YAML (this
//! crate does not depend on the config loader). Shared by the tests and
//! the benches, which each use part of it.
#![allow(dead_code)]

use serde_yaml::Value;
use servobus_kinematics::{Geometry, Spec};

/// A shipped robot: its model (limits set, radians) and joint names.
pub struct Shipped {
    pub model: Geometry,
    pub names: Vec<String>,
}

/// Loads `configs/robots/<name>.yaml` (angles in degrees).
pub fn shipped(name: &str) -> Shipped {
    let path = format!(
        "{}/../../configs/robots/{name}.yaml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).expect("shipped robot file");
    let doc: Value = serde_yaml::from_str(&text).expect("valid YAML");
    let spec: Spec =
        serde_yaml::from_value(doc["kinematics"].clone()).expect("a kinematics section");
    let mut names = Vec::new();
    let mut limits = Vec::new();
    for bus in doc["buses"].as_sequence().expect("buses") {
        for j in bus["joints"].as_sequence().expect("joints") {
            names.push(j["name"].as_str().expect("name").to_owned());
            let lim = |k: &str| j[k].as_f64().expect("limit").to_radians();
            limits.push((lim("min"), lim("max")));
        }
    }
    let mut model = Geometry::new(&spec, names.iter().map(String::as_str), 1f64.to_radians())
        .expect("valid geometry");
    for (i, (lo, hi)) in limits.into_iter().enumerate() {
        model.set_limits(i, lo, hi);
    }
    Shipped { model, names }
}

/// Joint angles in robot order from `(name, degrees)` pairs; others 0.
pub fn pose(s: &Shipped, angles: &[(&str, f64)]) -> Vec<f64> {
    s.names
        .iter()
        .map(|n| {
            angles
                .iter()
                .find(|(a, _)| a == n)
                .map_or(0.0, |(_, d)| d.to_radians())
        })
        .collect()
}

/// The shipped hexapod's legs (`foot_<leg>`), left side first.
pub const LEGS: [&str; 6] = [
    "front_left",
    "middle_left",
    "rear_left",
    "front_right",
    "middle_right",
    "rear_right",
];

/// The hexapod standing: every femur at 30 deg, every tibia at -60 deg.
pub fn standing(s: &Shipped) -> Vec<f64> {
    let stand: Vec<(&str, f64)> = s
        .names
        .iter()
        .filter_map(|n| match n.rsplit('_').next() {
            Some("femur") => Some((n.as_str(), 30.0)),
            Some("tibia") => Some((n.as_str(), -60.0)),
            _ => None,
        })
        .collect();
    pose(s, &stand)
}
