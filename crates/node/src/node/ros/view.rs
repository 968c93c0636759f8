//! A whole cycle as ROS 2 messages give it: radians, per joint of the
//! robot.

use servobus_robot::config::Units;

use crate::node::state::Done;

/// One cycle in rad and rad/s.
pub(super) struct View {
    /// When the cycle's state was gathered, ns since the UNIX epoch.
    pub stamp_ns: i64,
    /// The path at the time of the reading.
    pub planned: Vec<f64>,
    /// The goals sent.
    pub commanded: Vec<f64>,
    /// The readings.
    pub measured: Vec<Option<f64>>,
    /// The measured velocities.
    pub velocity: Vec<f64>,
}

impl View {
    /// The cycle `done`, whose angles are in `units`.
    pub fn of(done: &Done, units: Units) -> Self {
        let rad = |v: &[f64]| -> Vec<f64> { v.iter().map(|&a| units.to_rad(a)).collect() };
        let m = &done.msg;
        View {
            stamp_ns: m.stamp_ns,
            planned: rad(&done.planned),
            commanded: rad(&m.commanded),
            measured: m
                .measured
                .iter()
                .map(|a| a.map(|a| units.to_rad(a)))
                .collect(),
            velocity: rad(&m.velocity),
        }
    }
}
