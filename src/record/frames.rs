//! Where the robot's named frames (an arm's `tool`, a hexapod's
//! `foot_<leg>`) are during a run, by forward kinematics of the measured
//! joint angles: the log's spatial columns and the plot's views in space.

use servobus_config::Units;
use servobus_kinematics::{Geometry, Poses};
use servobus_robot::CycleSample;

/// Forward kinematics of the latest measured angle of every joint, kept
/// up to date one cycle sample at a time.
///
/// A sample carries one bus's joints: the other buses' joints keep their
/// last readings. Until every joint has been read once there is no pose.
pub struct FrameTracker {
    model: Geometry,
    poses: Poses,
    /// Named frames, in the model's order.
    names: Vec<String>,
    /// The latest measured angle of each joint, radians, robot order.
    angles: Vec<f64>,
    read: Vec<bool>,
    /// The units of the samples' angles.
    units: Units,
    /// Each frame's position, mm in the base frame, once every joint has
    /// been read.
    positions: Option<Vec<[f64; 3]>>,
}

impl FrameTracker {
    /// The tracker of `model`'s named frames, for samples whose angles are
    /// in `units`; `None` when the model names no frame.
    pub fn new(model: Geometry, units: Units) -> Option<Self> {
        let names: Vec<String> = (0..model.frame_count())
            .filter_map(|i| model.frame_name(i).map(str::to_owned))
            .collect();
        if names.is_empty() {
            return None;
        }
        let joints = model.joint_count();
        Some(FrameTracker {
            poses: Poses::new(&model),
            names,
            angles: vec![0.0; joints],
            read: vec![false; joints],
            units,
            positions: None,
            model,
        })
    }

    /// The named frames, in the order of [`positions`](Self::positions).
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Takes `sample`'s readings and recomputes the frames' positions.
    pub fn update(&mut self, sample: &CycleSample) {
        for j in sample.joints() {
            if let (Some(m), Some(angle), Some(read)) = (
                j.measured,
                self.angles.get_mut(j.joint),
                self.read.get_mut(j.joint),
            ) {
                *angle = self.units.to_rad(m);
                *read = true;
            }
        }
        if !self.read.iter().all(|&r| r) {
            return;
        }
        self.model.forward(&self.angles, &mut self.poses);
        let positions = self
            .positions
            .get_or_insert_with(|| vec![[0.0; 3]; self.names.len()]);
        for (k, p) in positions.iter_mut().enumerate() {
            if let Some(pose) = self.poses.frame(k) {
                let t = pose.translation.vector;
                *p = [t.x, t.y, t.z];
            }
        }
    }

    /// Each named frame's position (mm, base frame) at the latest sample;
    /// `None` until every joint has been read.
    pub fn positions(&self) -> Option<&[[f64; 3]]> {
        self.positions.as_deref()
    }
}
