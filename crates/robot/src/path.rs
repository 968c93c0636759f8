//! Planned paths, for programs that show or check them: a
//! [`Trajectory`](crate::Trajectory)'s per-joint states and summaries, and
//! how a recording is followed within the joint limits ([`track_with`]:
//! where the filter had to depart from it, and why).

pub use servobus_trajectory::{
    track_with, Departure, JointState, JointSummary, Quantity, TrackOptions, Tracked,
};
