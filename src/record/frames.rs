//! The log's spatial columns: where the robot's named frames (an arm's
//! `tool`, a hexapod's `foot_<leg>`) are, by forward kinematics of the
//! measured joint angles.

use servobus_kinematics::{Geometry, Poses};
use servobus_runtime::config::Units;
use servobus_runtime::CycleSample;

/// Forward kinematics of the latest measured angle of every joint, kept
/// up to date one cycle sample at a time.
///
/// A sample carries one bus's joints: the other buses' joints keep their
/// last readings. Until every joint has been read once there is no pose,
/// and the columns stay empty.
pub struct FrameColumns {
    model: Geometry,
    poses: Poses,
    /// Named frames, in the model's order.
    names: Vec<String>,
    /// The latest measured angle of each joint, radians, robot order.
    angles: Vec<f64>,
    read: Vec<bool>,
    /// The units of the samples' angles.
    units: Units,
    /// The current sample's cells: x, y and z (mm) of each frame.
    cells: Vec<String>,
}

impl FrameColumns {
    /// The columns of `model`'s named frames, for samples whose angles are
    /// in `units`; `None` when the model names no frame.
    pub fn new(model: Geometry, units: Units) -> Option<Self> {
        let names: Vec<String> = (0..model.frame_count())
            .filter_map(|i| model.frame_name(i).map(str::to_owned))
            .collect();
        if names.is_empty() {
            return None;
        }
        let joints = model.joint_count();
        Some(FrameColumns {
            poses: Poses::new(&model),
            cells: vec![String::new(); 3 * names.len()],
            names,
            angles: vec![0.0; joints],
            read: vec![false; joints],
            units,
            model,
        })
    }

    /// The header cells: `<frame>_x_mm`, `<frame>_y_mm`, `<frame>_z_mm`
    /// for each named frame.
    pub fn header(&self) -> impl Iterator<Item = String> + '_ {
        self.names
            .iter()
            .flat_map(|n| ["x", "y", "z"].map(move |axis| format!("{n}_{axis}_mm")))
    }

    /// Takes `sample`'s readings and recomputes the frames' cells.
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
        for (k, cells) in self.cells.chunks_mut(3).enumerate() {
            if let Some(pose) = self.poses.frame(k) {
                let t = pose.translation.vector;
                for (cell, v) in cells.iter_mut().zip([t.x, t.y, t.z]) {
                    *cell = format!("{v:.3}");
                }
            }
        }
    }

    /// The current sample's cells, in the header's order (empty before
    /// every joint has been read).
    pub fn cells(&self) -> &[String] {
        &self.cells
    }
}
