//! ROS 2 topics into the stream: `<ns>/joint_commands` (JointState or
//! Float64MultiArray: live targets) and `<ns>/joint_trajectory`
//! (JointTrajectory: a timed chunk, [`super::trajectory`]).
//!
//! Every message's times are put on the node's stream clock (seconds
//! since the node started, the clock of the `target` key's unstamped
//! targets): a ROS time is nanoseconds since the UNIX epoch, so it is
//! the arrival's stream time minus its age on the system clock.
//!
//! | message | stamp in the stream | latency counted from |
//! |---|---|---|
//! | JointState | `header.stamp` (never later than the arrival); zero: the arrival | `header.stamp`, else the rmw_zenoh attachment's source time, else the arrival |
//! | Float64MultiArray | the arrival | the attachment's source time, else the arrival |
//! | JointTrajectory | its points at `header.stamp` (zero: the arrival) + `time_from_start` | the attachment's source time, else the arrival |
//!
//! A payload that is not the message, or a trajectory that cannot be
//! followed, is counted in `malformed`, said on stderr, and moves nothing.

use std::sync::atomic::Ordering;
use std::time::{Duration, Instant, SystemTime};

use servobus_robot::{LiveTarget, TargetError};

use super::trajectory::{plan, Planned, RosRobot, Start};
use crate::node::relay::{deliver, Inputs};
use crate::node::{lock, unix_ns, Shared};
use crate::ros2::{
    Attachment, CdrMessage, Float64MultiArray, JointStateMessage, JointTrajectory, RosTime,
};

/// When a message came, on the clocks its times are turned into.
#[derive(Debug, Clone, Copy)]
pub(in crate::node) struct Arrival {
    /// The node's stream clock, s.
    pub stream: f64,
    /// The system clock, ns since the UNIX epoch.
    pub unix_ns: i64,
    /// The monotonic clock.
    pub instant: Instant,
}

impl Arrival {
    /// Now, on the clocks of `shared`.
    pub fn now(shared: &Shared) -> Self {
        Arrival {
            stream: shared.stream_now(),
            unix_ns: unix_ns(SystemTime::now()),
            instant: Instant::now(),
        }
    }

    /// The ROS time `t` on the stream clock.
    pub fn stream_of(&self, t: RosTime) -> f64 {
        self.stream - (self.unix_ns - t.as_ns()) as f64 * 1e-9
    }

    /// The moment of the ROS time `ns` on the monotonic clock, at the
    /// latest the arrival.
    pub fn instant_of(&self, ns: i64) -> Instant {
        let ago = u64::try_from(self.unix_ns.saturating_sub(ns)).unwrap_or(0);
        self.instant
            .checked_sub(Duration::from_nanos(ago))
            .unwrap_or(self.instant)
    }

    /// When a sample was published, from its rmw_zenoh attachment; the
    /// arrival without one.
    pub fn published(&self, attachment: Option<&[u8]>) -> Instant {
        attachment
            .and_then(|a| Attachment::decode(a).ok())
            .map_or(self.instant, |a| self.instant_of(a.stamp_ns))
    }
}

/// What the topics' callbacks hold: the loop's inputs, the node's shared
/// state and the robot's joints.
pub(in crate::node) struct Context {
    /// The loop's inputs.
    pub to: Inputs,
    /// What the node's callbacks share.
    pub shared: std::sync::Arc<Shared>,
    /// The robot's joints.
    pub robot: RosRobot,
}

impl Context {
    /// Counts a message that moves nothing and says why on stderr.
    pub fn malformed(&self, topic: &str, why: &dyn std::fmt::Display) {
        self.shared.counts.malformed.fetch_add(1, Ordering::Relaxed);
        eprintln!("ROS 2 {topic}: {why}; ignored");
    }

    /// Counts a message the stream took, or says why it refused it (the
    /// stream counts its refusals for the report).
    fn taken(
        &self,
        topic: &str,
        sent: Result<usize, TargetError>,
        count: &std::sync::atomic::AtomicU64,
    ) {
        match sent {
            Ok(_) => {
                count.fetch_add(1, Ordering::Relaxed);
            }
            Err(why) => eprintln!("ROS 2 {topic}: {why}; refused"),
        }
    }
}

/// `joint_commands` as `sensor_msgs/msg/JointState`: the positions named,
/// a live target.
pub(in crate::node) fn take_joint_state(payload: &[u8], attachment: Option<&[u8]>, cx: &Context) {
    let topic = "joint_commands (JointState)";
    let at = Arrival::now(&cx.shared);
    let msg = match JointStateMessage::decode(payload) {
        Ok(m) => m,
        Err(why) => return cx.malformed(topic, &why),
    };
    if msg.position.is_empty() || msg.position.len() != msg.name.len() {
        let why = format!(
            "{} positions for {} names: give one position per joint named",
            msg.position.len(),
            msg.name.len()
        );
        return cx.malformed(topic, &why);
    }
    let stamp = msg.header.stamp;
    let (stamp, taken) = if stamp.is_zero() {
        (at.stream, at.published(attachment))
    } else {
        (
            at.stream_of(stamp).min(at.stream),
            at.instant_of(stamp.as_ns()),
        )
    };
    let joints = msg.name.into_iter().zip(msg.position).collect();
    let target = LiveTarget::named(stamp, joints).taken_at(taken);
    let sent = deliver(&cx.to, &cx.shared, "joint_commands", |t| t.send(target));
    cx.taken(topic, sent, &cx.shared.counts.targets);
}

/// `joint_commands` as `std_msgs/msg/Float64MultiArray`: every joint's
/// position in the robot's order (from the layout's `data_offset`), a
/// live target.
pub(in crate::node) fn take_multi_array(payload: &[u8], attachment: Option<&[u8]>, cx: &Context) {
    let topic = "joint_commands (Float64MultiArray)";
    let at = Arrival::now(&cx.shared);
    let msg = match Float64MultiArray::decode(payload) {
        Ok(m) => m,
        Err(why) => return cx.malformed(topic, &why),
    };
    let offset = msg.layout.data_offset as usize;
    let Some(data) = msg.data.get(offset..) else {
        let why = format!("data_offset {offset} is past the {} values", msg.data.len());
        return cx.malformed(topic, &why);
    };
    let target = LiveTarget::all(at.stream, data.to_vec()).taken_at(at.published(attachment));
    let sent = deliver(&cx.to, &cx.shared, "joint_commands", |t| t.send(target));
    cx.taken(topic, sent, &cx.shared.counts.targets);
}

/// Plans `traj` arriving `at` from the joints' commanded state.
///
/// # Errors
/// The refusal, as [`plan`]'s.
pub(in crate::node) fn plan_arrival(
    traj: &JointTrajectory,
    at: &Arrival,
    cx: &Context,
) -> Result<Planned, super::trajectory::Refusal> {
    let start = if traj.header.stamp.is_zero() {
        at.stream
    } else {
        at.stream_of(traj.header.stamp)
    };
    let latest = lock(&cx.shared.latest).clone();
    let heading = |j: usize| latest.position_at(j, at.instant);
    let from = Start {
        now: at.stream,
        start,
        position: &heading,
    };
    plan(traj, &cx.robot, &from)
}

/// Sends a planned trajectory into the stream: the empty target stamped
/// `now` (the arrival, stream clock), then the chunk (see
/// [`super::trajectory`]).
///
/// # Errors
/// The stream's refusal, or [`TargetError::Ended`].
pub(in crate::node) fn send_planned(
    planned: &Planned,
    now: f64,
    taken: Instant,
    (to, shared, robot): (&Inputs, &Shared, &RosRobot),
) -> Result<usize, TargetError> {
    let chunk = planned.chunk(robot).taken_at(taken);
    deliver(to, shared, "joint_trajectory", |t| {
        t.send(LiveTarget::named(now, Vec::new()))?;
        t.send_chunk(chunk)
    })
}

/// `joint_trajectory`: a timed chunk through the trajectory's points.
pub(in crate::node) fn take_trajectory(payload: &[u8], attachment: Option<&[u8]>, cx: &Context) {
    let topic = "joint_trajectory";
    let at = Arrival::now(&cx.shared);
    let traj = match JointTrajectory::decode(payload) {
        Ok(t) => t,
        Err(why) => return cx.malformed(topic, &why),
    };
    let planned = match plan_arrival(&traj, &at, cx) {
        Ok(p) => p,
        Err(why) => return cx.malformed(topic, &why),
    };
    let into = (&cx.to, &*cx.shared, &cx.robot);
    let sent = send_planned(&planned, at.stream, at.published(attachment), into);
    cx.taken(topic, sent, &cx.shared.counts.trajectories);
}
