//! The multi-DOF half of a `FollowJointTrajectory` goal and feedback:
//! `trajectory_msgs/msg/MultiDOFJointTrajectory` and the `geometry_msgs`
//! it is made of. servobus drives single-DOF joints only; these are read
//! so that a goal with multi-DOF joints can be refused with a reason, and
//! written (empty) in the feedback ROS expects.

use super::cdr::{CdrError, CdrMessage, CdrReader, CdrWriter};
use super::hash::TypeDescription;
use super::msgs::{Header, RosDuration};
use super::types;

/// `geometry_msgs/msg/Vector3`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RosVector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

impl CdrMessage for RosVector3 {
    const MIN_WIRE_SIZE: usize = 24;
    fn description() -> &'static TypeDescription {
        &types::VECTOR3
    }
    fn write(&self, w: &mut CdrWriter) {
        w.f64(self.x);
        w.f64(self.y);
        w.f64(self.z);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(RosVector3 {
            x: r.f64("x")?,
            y: r.f64("y")?,
            z: r.f64("z")?,
        })
    }
}

/// `geometry_msgs/msg/Quaternion`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RosQuaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Default for RosQuaternion {
    /// The identity rotation, as ROS defaults it.
    fn default() -> Self {
        RosQuaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

impl CdrMessage for RosQuaternion {
    const MIN_WIRE_SIZE: usize = 32;
    fn description() -> &'static TypeDescription {
        &types::QUATERNION
    }
    fn write(&self, w: &mut CdrWriter) {
        w.f64(self.x);
        w.f64(self.y);
        w.f64(self.z);
        w.f64(self.w);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(RosQuaternion {
            x: r.f64("x")?,
            y: r.f64("y")?,
            z: r.f64("z")?,
            w: r.f64("w")?,
        })
    }
}

/// `geometry_msgs/msg/Transform`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RosTransform {
    /// Translation.
    pub translation: RosVector3,
    /// Rotation.
    pub rotation: RosQuaternion,
}

impl CdrMessage for RosTransform {
    const MIN_WIRE_SIZE: usize = 56;
    fn description() -> &'static TypeDescription {
        &types::TRANSFORM
    }
    fn write(&self, w: &mut CdrWriter) {
        self.translation.write(w);
        self.rotation.write(w);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(RosTransform {
            translation: r.nested("translation")?,
            rotation: r.nested("rotation")?,
        })
    }
}

/// `geometry_msgs/msg/Twist`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RosTwist {
    /// Linear part.
    pub linear: RosVector3,
    /// Angular part.
    pub angular: RosVector3,
}

impl CdrMessage for RosTwist {
    const MIN_WIRE_SIZE: usize = 48;
    fn description() -> &'static TypeDescription {
        &types::TWIST
    }
    fn write(&self, w: &mut CdrWriter) {
        self.linear.write(w);
        self.angular.write(w);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(RosTwist {
            linear: r.nested("linear")?,
            angular: r.nested("angular")?,
        })
    }
}

/// `trajectory_msgs/msg/MultiDOFJointTrajectoryPoint`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MultiDofJointTrajectoryPoint {
    /// One transform per multi-DOF joint.
    pub transforms: Vec<RosTransform>,
    /// Velocities.
    pub velocities: Vec<RosTwist>,
    /// Accelerations.
    pub accelerations: Vec<RosTwist>,
    /// When the point is to be reached.
    pub time_from_start: RosDuration,
}

impl MultiDofJointTrajectoryPoint {
    /// Whether the point holds no joint values (its time aside).
    pub fn is_empty(&self) -> bool {
        self.transforms.is_empty() && self.velocities.is_empty() && self.accelerations.is_empty()
    }
}

impl CdrMessage for MultiDofJointTrajectoryPoint {
    const MIN_WIRE_SIZE: usize = 20;
    fn description() -> &'static TypeDescription {
        &types::MULTI_DOF_POINT
    }
    fn write(&self, w: &mut CdrWriter) {
        w.seq(&self.transforms);
        w.seq(&self.velocities);
        w.seq(&self.accelerations);
        self.time_from_start.write(w);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(MultiDofJointTrajectoryPoint {
            transforms: r.seq("transforms")?,
            velocities: r.seq("velocities")?,
            accelerations: r.seq("accelerations")?,
            time_from_start: r.nested("time_from_start")?,
        })
    }
}

/// `trajectory_msgs/msg/MultiDOFJointTrajectory`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MultiDofJointTrajectory {
    /// Start time and frame.
    pub header: Header,
    /// The multi-DOF joints.
    pub joint_names: Vec<String>,
    /// The points.
    pub points: Vec<MultiDofJointTrajectoryPoint>,
}

impl MultiDofJointTrajectory {
    /// Whether it names no joint and holds no point: what servobus, with
    /// single-DOF joints only, accepts.
    pub fn is_empty(&self) -> bool {
        self.joint_names.is_empty() && self.points.is_empty()
    }
}

impl CdrMessage for MultiDofJointTrajectory {
    const MIN_WIRE_SIZE: usize = 21;
    fn description() -> &'static TypeDescription {
        &types::MULTI_DOF_TRAJECTORY
    }
    fn write(&self, w: &mut CdrWriter) {
        self.header.write(w);
        w.string_seq(&self.joint_names);
        w.seq(&self.points);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(MultiDofJointTrajectory {
            header: r.nested("header")?,
            joint_names: r.string_seq("joint_names")?,
            points: r.seq("points")?,
        })
    }
}
