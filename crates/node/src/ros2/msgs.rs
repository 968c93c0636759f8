//! The messages of ROS 2's topics that servobus reads and writes:
//! `builtin_interfaces` times, `std_msgs/msg/Header`,
//! `sensor_msgs/msg/JointState`, `std_msgs/msg/Float64MultiArray` and
//! `trajectory_msgs/msg/JointTrajectory`. Field names and order are ROS's;
//! angles are whatever the sender put there (rad for the joint
//! trajectory controller's topics).

use super::cdr::{CdrError, CdrMessage, CdrReader, CdrWriter};
use super::hash::TypeDescription;
use super::types;

/// `builtin_interfaces/msg/Time`: seconds and nanoseconds since the UNIX
/// epoch (or since a node's clock started, for simulated time).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RosTime {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds, below 1e9 when well formed.
    pub nanosec: u32,
}

impl RosTime {
    /// The time `ns` nanoseconds after the epoch, seconds clamped to i32.
    pub fn from_ns(ns: i64) -> Self {
        let sec = ns.div_euclid(1_000_000_000);
        let nanosec = ns.rem_euclid(1_000_000_000);
        RosTime {
            sec: i32::try_from(sec).unwrap_or(if sec < 0 { i32::MIN } else { i32::MAX }),
            nanosec: u32::try_from(nanosec).unwrap_or(0),
        }
    }

    /// Nanoseconds since the epoch.
    pub fn as_ns(&self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }

    /// Whether this is the zero time, which a trajectory's header uses to
    /// say "start now".
    pub fn is_zero(&self) -> bool {
        self.sec == 0 && self.nanosec == 0
    }
}

impl CdrMessage for RosTime {
    const MIN_WIRE_SIZE: usize = 8;
    fn description() -> &'static TypeDescription {
        &types::TIME
    }
    fn write(&self, w: &mut CdrWriter) {
        w.i32(self.sec);
        w.u32(self.nanosec);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(RosTime {
            sec: r.i32("sec")?,
            nanosec: r.u32("nanosec")?,
        })
    }
}

/// `builtin_interfaces/msg/Duration`: `sec + nanosec / 1e9` seconds (a
/// negative duration has negative `sec` and `nanosec` still positive).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RosDuration {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds added to `sec`.
    pub nanosec: u32,
}

impl RosDuration {
    /// The duration in seconds.
    pub fn as_secs_f64(&self) -> f64 {
        f64::from(self.sec) + f64::from(self.nanosec) * 1e-9
    }

    /// The duration closest to `seconds` (clamped to what i32 seconds
    /// hold; NaN is zero).
    pub fn from_secs_f64(seconds: f64) -> Self {
        let ns = (seconds * 1e9).round();
        let ns = if ns.is_nan() { 0 } else { ns as i64 };
        let t = RosTime::from_ns(ns);
        RosDuration {
            sec: t.sec,
            nanosec: t.nanosec,
        }
    }
}

impl CdrMessage for RosDuration {
    const MIN_WIRE_SIZE: usize = 8;
    fn description() -> &'static TypeDescription {
        &types::DURATION
    }
    fn write(&self, w: &mut CdrWriter) {
        w.i32(self.sec);
        w.u32(self.nanosec);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(RosDuration {
            sec: r.i32("sec")?,
            nanosec: r.u32("nanosec")?,
        })
    }
}

/// `std_msgs/msg/Header`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Header {
    /// When the data was taken (or, for a trajectory, when it starts).
    pub stamp: RosTime,
    /// The coordinate frame (empty for joint-space messages).
    pub frame_id: String,
}

impl CdrMessage for Header {
    const MIN_WIRE_SIZE: usize = 13;
    fn description() -> &'static TypeDescription {
        &types::HEADER
    }
    fn write(&self, w: &mut CdrWriter) {
        self.stamp.write(w);
        w.string(&self.frame_id);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Header {
            stamp: r.nested("stamp")?,
            frame_id: r.string("frame_id")?,
        })
    }
}

/// One `sensor_msgs/msg/JointState`, borrowed, as servobus publishes it:
/// positions in rad, velocities in rad/s (either may be empty), stamped
/// in ns since the UNIX epoch. [`JointStateMessage`] is the owned form,
/// which a received message decodes into.
#[derive(Debug, Clone, PartialEq)]
pub struct JointState<'a> {
    /// Time of the measurement, ns since the UNIX epoch.
    pub stamp_ns: i64,
    /// The header's frame (empty for joint states, as is usual).
    pub frame_id: &'a str,
    /// Joint names.
    pub names: &'a [String],
    /// Positions, rad.
    pub position: &'a [f64],
    /// Velocities, rad/s.
    pub velocity: &'a [f64],
    /// Efforts (servobus publishes none).
    pub effort: &'a [f64],
}

impl JointState<'_> {
    /// The CDR payload, encapsulation header first.
    pub fn encode(&self) -> Vec<u8> {
        let mut w = CdrWriter::new();
        RosTime::from_ns(self.stamp_ns).write(&mut w);
        w.string(self.frame_id);
        write_joint_values(
            &mut w,
            self.names,
            [self.position, self.velocity, self.effort],
        );
        w.finish()
    }
}

/// A joint state's names and its three value sequences.
fn write_joint_values(w: &mut CdrWriter, names: &[String], values: [&[f64]; 3]) {
    w.string_seq(names);
    for v in values {
        w.f64_seq(v);
    }
}

/// `sensor_msgs/msg/JointState`, owned: what a `joint_commands` sample
/// decodes into. All sequences should be as long as `name`, or empty.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointStateMessage {
    /// Stamp and frame.
    pub header: Header,
    /// Joint names.
    pub name: Vec<String>,
    /// Positions (rad or m).
    pub position: Vec<f64>,
    /// Velocities (rad/s or m/s).
    pub velocity: Vec<f64>,
    /// Efforts (N·m or N).
    pub effort: Vec<f64>,
}

impl CdrMessage for JointStateMessage {
    const MIN_WIRE_SIZE: usize = 29;
    fn description() -> &'static TypeDescription {
        &types::JOINT_STATE
    }
    fn write(&self, w: &mut CdrWriter) {
        self.header.write(w);
        write_joint_values(
            w,
            &self.name,
            [&self.position, &self.velocity, &self.effort],
        );
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(JointStateMessage {
            header: r.nested("header")?,
            name: r.string_seq("name")?,
            position: r.f64_seq("position")?,
            velocity: r.f64_seq("velocity")?,
            effort: r.f64_seq("effort")?,
        })
    }
}

/// `std_msgs/msg/MultiArrayDimension`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct MultiArrayDimension {
    /// The dimension's name.
    pub label: String,
    /// Its size.
    pub size: u32,
    /// Its stride.
    pub stride: u32,
}

impl CdrMessage for MultiArrayDimension {
    const MIN_WIRE_SIZE: usize = 13;
    fn description() -> &'static TypeDescription {
        &types::MULTI_ARRAY_DIMENSION
    }
    fn write(&self, w: &mut CdrWriter) {
        w.string(&self.label);
        w.u32(self.size);
        w.u32(self.stride);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(MultiArrayDimension {
            label: r.string("label")?,
            size: r.u32("size")?,
            stride: r.u32("stride")?,
        })
    }
}

/// `std_msgs/msg/MultiArrayLayout`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct MultiArrayLayout {
    /// The dimensions, outermost first.
    pub dim: Vec<MultiArrayDimension>,
    /// Where the data starts in `data`.
    pub data_offset: u32,
}

impl CdrMessage for MultiArrayLayout {
    const MIN_WIRE_SIZE: usize = 8;
    fn description() -> &'static TypeDescription {
        &types::MULTI_ARRAY_LAYOUT
    }
    fn write(&self, w: &mut CdrWriter) {
        w.seq(&self.dim);
        w.u32(self.data_offset);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(MultiArrayLayout {
            dim: r.seq("dim")?,
            data_offset: r.u32("data_offset")?,
        })
    }
}

/// `std_msgs/msg/Float64MultiArray`: on `joint_commands`, one position per
/// joint in the robot's joint order (the layout is usually empty).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Float64MultiArray {
    /// How `data` is laid out.
    pub layout: MultiArrayLayout,
    /// The values.
    pub data: Vec<f64>,
}

impl CdrMessage for Float64MultiArray {
    const MIN_WIRE_SIZE: usize = 12;
    fn description() -> &'static TypeDescription {
        &types::FLOAT64_MULTI_ARRAY
    }
    fn write(&self, w: &mut CdrWriter) {
        self.layout.write(w);
        w.f64_seq(&self.data);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Float64MultiArray {
            layout: r.nested("layout")?,
            data: r.f64_seq("data")?,
        })
    }
}

/// `trajectory_msgs/msg/JointTrajectoryPoint`: one point per joint of the
/// trajectory's `joint_names`, each sequence as long as that list or
/// empty when not given.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointTrajectoryPoint {
    /// Positions (rad or m).
    pub positions: Vec<f64>,
    /// Velocities.
    pub velocities: Vec<f64>,
    /// Accelerations.
    pub accelerations: Vec<f64>,
    /// Efforts.
    pub effort: Vec<f64>,
    /// When the point is to be reached, from the trajectory's start.
    pub time_from_start: RosDuration,
}

impl CdrMessage for JointTrajectoryPoint {
    const MIN_WIRE_SIZE: usize = 24;
    fn description() -> &'static TypeDescription {
        &types::JOINT_TRAJECTORY_POINT
    }
    fn write(&self, w: &mut CdrWriter) {
        w.f64_seq(&self.positions);
        w.f64_seq(&self.velocities);
        w.f64_seq(&self.accelerations);
        w.f64_seq(&self.effort);
        self.time_from_start.write(w);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(JointTrajectoryPoint {
            positions: r.f64_seq("positions")?,
            velocities: r.f64_seq("velocities")?,
            accelerations: r.f64_seq("accelerations")?,
            effort: r.f64_seq("effort")?,
            time_from_start: r.nested("time_from_start")?,
        })
    }
}

/// `trajectory_msgs/msg/JointTrajectory`: the topic interface of
/// joint_trajectory_controller (`header.stamp` zero means "start now").
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointTrajectory {
    /// The start time and frame.
    pub header: Header,
    /// The joints the points give values for, in their order.
    pub joint_names: Vec<String>,
    /// The points, in time order.
    pub points: Vec<JointTrajectoryPoint>,
}

impl CdrMessage for JointTrajectory {
    const MIN_WIRE_SIZE: usize = 21;
    fn description() -> &'static TypeDescription {
        &types::JOINT_TRAJECTORY
    }
    fn write(&self, w: &mut CdrWriter) {
        self.header.write(w);
        w.string_seq(&self.joint_names);
        w.seq(&self.points);
    }
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(JointTrajectory {
            header: r.nested("header")?,
            joint_names: r.string_seq("joint_names")?,
            points: r.seq("points")?,
        })
    }
}
