//! Why a plan can fail.

use core::fmt;

/// A quantity limited per joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Quantity {
    /// Position (a keyframe or the path leaves `[min_position, max_position]`).
    Position,
    /// Velocity (`max_velocity`).
    Velocity,
    /// Acceleration (`max_acceleration`).
    Acceleration,
    /// Jerk (`max_jerk`).
    Jerk,
}

impl fmt::Display for Quantity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Quantity::Position => "position",
            Quantity::Velocity => "velocity",
            Quantity::Acceleration => "acceleration",
            Quantity::Jerk => "jerk",
        })
    }
}

/// Why [`plan`](crate::plan), [`retarget`](crate::retarget) or
/// [`stop`](crate::stop) refused.
///
/// Keyframe indices refer to the slice given to `plan` (0-based); joint
/// indices to the limits slice. With `repeat`, the index is the keyframe's
/// index in the list, whatever the cycle.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// No joint limits were given.
    #[error("no joints")]
    NoJoints,
    /// No keyframes were given.
    #[error("no keyframes")]
    NoKeyframes,
    /// A joint's limits are unusable (not finite, not positive, min > max).
    #[error("joint {joint}: invalid limits: {reason}")]
    InvalidLimits {
        /// Joint index.
        joint: usize,
        /// What is wrong.
        reason: &'static str,
    },
    /// A keyframe (or a target or state) has the wrong number of positions.
    #[error("keyframe {keyframe}: {actual} positions for {expected} joints")]
    WrongJointCount {
        /// Keyframe index (0 for a target or a state).
        keyframe: usize,
        /// Number of joints.
        expected: usize,
        /// Number of positions given.
        actual: usize,
    },
    /// A position, state or time is NaN or infinite.
    #[error("keyframe {keyframe}, joint {joint}: value is not finite")]
    NotFinite {
        /// Keyframe index.
        keyframe: usize,
        /// Joint index.
        joint: usize,
    },
    /// A keyframe position lies outside the joint's position limits.
    #[error("keyframe {keyframe}, joint {joint}: position {position} outside [{min}, {max}]")]
    OutOfRange {
        /// Keyframe index.
        keyframe: usize,
        /// Joint index.
        joint: usize,
        /// The position asked for.
        position: f64,
        /// Lower limit.
        min: f64,
        /// Upper limit.
        max: f64,
    },
    /// The first keyframe is the start (t = 0); it cannot have another time.
    #[error("keyframe 0 is the start and must be at 0, not {at}")]
    FirstKeyframeTime {
        /// The time given.
        at: f64,
    },
    /// A keyframe time is not after the previous keyframe's.
    #[error("keyframe {keyframe}: time {at} is not after the previous keyframe's time {previous}")]
    TimeNotIncreasing {
        /// Keyframe index.
        keyframe: usize,
        /// Its time.
        at: f64,
        /// When the previous keyframe is reached.
        previous: f64,
    },
    /// `repeat` was zero.
    #[error("repeat must be at least 1")]
    ZeroRepeat,
    /// A timed segment needs more than a limit allows. Use
    /// [`OnLimit::Stretch`](crate::OnLimit::Stretch) to stretch the timing
    /// instead (position violations cannot be stretched away).
    #[error(
        "keyframe {keyframe}, joint {joint}: peak {quantity} {peak} exceeds the limit {limit}"
    )]
    LimitExceeded {
        /// Index of the keyframe the offending segment arrives at.
        keyframe: usize,
        /// Joint index.
        joint: usize,
        /// Which limit.
        quantity: Quantity,
        /// The peak the segment needs (absolute value; for position the
        /// position reached).
        peak: f64,
        /// The limit.
        limit: f64,
    },
    /// Untimed keyframes before a timed one need more time than its `at`
    /// leaves (`OnLimit::Stretch` delays the timed keyframe instead).
    #[error("keyframe {keyframe}: needs {needed} s to reach but only {available} s are left")]
    TooSoon {
        /// Index of the timed keyframe.
        keyframe: usize,
        /// Shortest time to reach it.
        needed: f64,
        /// Time its `at` leaves.
        available: f64,
    },
}
