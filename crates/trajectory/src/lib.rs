//! Smooth, limit-respecting multi-joint paths through keyframes.
//!
//! servobus plays choreographies: lists of keyframes (a position for every
//! joint, optionally a time). This crate turns them into a path per joint
//! that the scheduler samples every control cycle. It knows nothing of
//! servos: positions, velocities, accelerations and jerks are in whatever
//! unit the caller uses consistently (radians, say), time is in seconds.
//!
//! What it computes:
//!
//! - **Untimed keyframes** ([`Keyframe::new`]): as fast as the
//!   [`JointLimits`] allow. Between two keyframes each joint follows a
//!   time-optimal trapezoidal velocity profile (no jerk limit) or 7-phase
//!   double-S (with one); the slowest joint sets the segment's duration and
//!   the others' profiles are stretched (lower cruise speed) so that every
//!   joint arrives together. Through intermediate keyframes a joint keeps
//!   moving when its motion continues, and stops only where it turns back,
//!   so velocity and acceleration are continuous and no joint overshoots the
//!   keyframes' positions.
//! - **Timed keyframes** ([`Keyframe::at`]): exactly at their times. By
//!   default shape-preserving: the same jerk-limited segment profiles as
//!   untimed motion, planned per joint to the given durations, so a joint
//!   never leaves the range of the keyframes around a segment and every
//!   motion that could stop at each keyframe on time is accepted. Also a
//!   C2 cubic spline, a monotone quintic or minimum-jerk quintic segments
//!   ([`TimedShape`]). A segment beyond a limit is an error naming the
//!   keyframe, joint, peak and limit ([`PlanError::LimitExceeded`],
//!   [`PlanError::TooSoon`]) unless [`OnLimit::Stretch`] is set.
//! - Mixed timed and untimed keyframes, and repeats ([`PlanOptions`]).
//! - **Recorded paths** ([`track`], [`track_with`]): a dense recording
//!   played as a cubic B-spline through its samples, exactly where it keeps
//!   within the limits (to the resolution of its numbers), and tracked
//!   forwards and backwards where it does not, so that the result is not
//!   late; each stretch off the recording is a [`Departure`] naming the
//!   limit broken there.
//! - **Online changes** from any state: [`retarget`] (to a new target,
//!   synchronised, jerk limited) and [`stop`] (to rest in minimal time).
//!
//! ```text
//!  velocity of one segment (double-S), j = jerk, a = acceleration phase
//!      ^      ______________
//!      |     /|            |\
//!      |    / |   cruise   | \
//!      |___/  |            |  \___
//!      +--j-a-j------------j-a-j---> t
//! ```
//!
//! A [`Trajectory`] is a list of polynomial pieces per joint. Sampling writes
//! into a caller-provided slice and never allocates; with a [`Cursor`] each
//! sample at an increasing time costs O(1), which is what a control loop
//! needs. [`Trajectory::joint_summary`] and [`Trajectory::segments`] give the
//! figures `servobus plan` prints.
//!
//! # Example
//!
//! ```
//! use servobus_trajectory::{plan, JointLimits, JointState, Keyframe, PlanOptions};
//!
//! // Two joints, rad-based limits; the second has no jerk limit.
//! let limits = [
//!     JointLimits::new(3.0, 20.0, Some(200.0)).with_positions(-2.0, 2.0),
//!     JointLimits::new(2.0, 10.0, None).with_positions(-1.5, 1.5),
//! ];
//! let keyframes = [
//!     Keyframe::new([0.0, 0.0]),
//!     Keyframe::new([0.5, 0.2]),           // as fast as allowed, no stop
//!     Keyframe::new([1.0, 0.4]),
//!     Keyframe::new([0.0, 0.0]).at(3.0),   // exactly at t = 3 s
//! ];
//! let traj = plan(&limits, &keyframes, &PlanOptions::default())?;
//! assert!((traj.duration() - 3.0).abs() < 1e-9);
//!
//! // The control loop: one cursor, one output buffer, no allocation.
//! let mut cursor = traj.cursor();
//! let mut out = [JointState::default(); 2];
//! let mut t = 0.0;
//! while t <= traj.duration() {
//!     traj.sample_with(&mut cursor, t, &mut out);
//!     assert!(out[0].velocity.abs() <= 3.0 + 1e-9);
//!     t += 0.005;
//! }
//! let peak = traj.joint_summary(0).expect("joint 0 exists");
//! assert!(peak.max_position <= 1.0 + 1e-9);
//! # Ok::<(), servobus_trajectory::PlanError>(())
//! ```
//!
//! # How time-optimality is checked
//!
//! `scripts/ruckig_compare.py` draws random rest-to-rest cases, solves them
//! with the Ruckig library (the `ruckig` package on PyPI) and writes the
//! cases and Ruckig's durations to `testdata/trajectory/ruckig.csv`; the
//! test `tests/ruckig.rs` plans the same cases and requires every duration
//! within 0.1 % of Ruckig's (they agree to about 1e-15). Regenerate the file with
//! `pip install ruckig && python3 scripts/ruckig_compare.py`.
#![warn(missing_docs)]

mod error;
mod follow;
mod limits;
mod online;
mod piece;
mod plan;
mod profile;
mod spline;
mod timed;
mod track;
mod trajectory;
mod untimed;

pub use error::{PlanError, Quantity};
pub use follow::{
    follow_steps, stop_position, stop_with_jerk_alone, Follower, Goal, TARGET_SPEED_SHARE,
};
pub use limits::JointLimits;
pub use online::{retarget, stop};
pub use plan::{plan, Keyframe, OnLimit, PlanOptions};
pub use spline::TimedShape;
pub use track::{track, track_with, Departure, TrackOptions, Tracked};
pub use trajectory::{Cursor, JointState, JointSummary, SegmentTiming, Trajectory};
