//! Keyframes in, trajectory out: splits the keyframe list into timed and
//! untimed sections and joins them at rest.
//!
//! Parts: `entries` (the checked, repeated keyframe list), `untimed_span`
//! (as fast as allowed, or scaled to arrive at a timed keyframe) and
//! `timed_span` (on time, shape-preserving or a spline, with the limit
//! checks and stretching).

mod entries;
mod timed_span;
mod untimed_span;

use crate::error::PlanError;
use crate::piece::Piece;
use crate::spline::TimedShape;
use crate::trajectory::SegmentTiming;
use crate::untimed::Scratch;
use crate::{JointLimits, Trajectory};
use entries::{expand, validate, Entry};

/// A pose to pass through: one position per joint, optionally at a time.
#[derive(Debug, Clone, PartialEq)]
pub struct Keyframe {
    /// One position per joint, in the limits' order and unit.
    pub positions: Vec<f64>,
    /// Time (s, from the start of the cycle) at which to be exactly here;
    /// `None`: as soon as the limits allow.
    pub at: Option<f64>,
    /// Interpolation of the timed segment arriving here; `None`: the
    /// plan's [`PlanOptions::shape`]. Ignored for untimed keyframes.
    pub shape: Option<TimedShape>,
}

impl Keyframe {
    /// An untimed keyframe.
    pub fn new(positions: impl Into<Vec<f64>>) -> Self {
        Keyframe {
            positions: positions.into(),
            at: None,
            shape: None,
        }
    }

    /// The same keyframe, reached at `at` seconds.
    pub fn at(mut self, at: f64) -> Self {
        self.at = Some(at);
        self
    }

    /// The same keyframe, with the segment arriving here shaped `shape`.
    pub fn shape(mut self, shape: TimedShape) -> Self {
        self.shape = Some(shape);
        self
    }
}

/// What to do when a timed segment would exceed a limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum OnLimit {
    /// Refuse with [`PlanError::LimitExceeded`] or [`PlanError::TooSoon`].
    #[default]
    Error,
    /// Stretch the timing of the offending segments (and delay every later
    /// keyframe by as much) until the limits hold.
    Stretch,
}

/// Options of [`plan`].
#[derive(Debug, Clone, PartialEq)]
pub struct PlanOptions {
    /// Default interpolation of timed segments.
    pub shape: TimedShape,
    /// Timed segments beyond a limit: error or stretch.
    pub on_limit: OnLimit,
    /// How many times the keyframe list is played (>= 1). Between cycles the
    /// last keyframe moves on to the first one (untimed) unless they are
    /// equal; a cycle's times count from its first keyframe's arrival.
    pub repeat: u32,
    /// Stop at every untimed keyframe instead of passing through (the
    /// slower, simpler motion; mostly useful for comparison).
    pub stop_at_keyframes: bool,
}

impl Default for PlanOptions {
    fn default() -> Self {
        PlanOptions {
            shape: TimedShape::ShapePreserving,
            on_limit: OnLimit::Error,
            repeat: 1,
            stop_at_keyframes: false,
        }
    }
}

/// Plans a trajectory through `keyframes` under `limits`.
///
/// Consecutive timed keyframes are interpolated with their
/// [`TimedShape`]; untimed ones are passed through as fast as the limits
/// allow, all joints arriving at each keyframe together. Untimed keyframes
/// followed by a timed one are slowed down uniformly to arrive exactly on
/// time. Timed and untimed sections join at rest.
///
/// # Errors
///
/// Invalid limits or keyframes ([`PlanError::InvalidLimits`],
/// [`PlanError::WrongJointCount`], [`PlanError::NotFinite`],
/// [`PlanError::OutOfRange`], [`PlanError::FirstKeyframeTime`],
/// [`PlanError::TimeNotIncreasing`], [`PlanError::ZeroRepeat`]); a timed
/// segment beyond a limit ([`PlanError::LimitExceeded`],
/// [`PlanError::TooSoon`]) unless [`OnLimit::Stretch`] is set.
pub fn plan(
    limits: &[JointLimits],
    keyframes: &[Keyframe],
    options: &PlanOptions,
) -> Result<Trajectory, PlanError> {
    validate(limits, keyframes, options)?;
    let entries = expand(keyframes, options);
    let mut sections = Sections::new(limits, &entries, options);
    let last = entries.len() - 1;
    let mut i = 0;
    while i < last {
        let j = if entries[i + 1].at.is_some() {
            sections.timed(i)?
        } else {
            sections.untimed(i)?
        };
        sections.rebase(i, j);
        i = j;
    }
    Ok(sections.finish())
}

/// The planner's state while it walks the expanded list section by
/// section: the pieces so far, every entry's arrival, and where the `at`s
/// count from.
struct Sections<'a> {
    limits: &'a [JointLimits],
    entries: &'a [Entry<'a>],
    options: &'a PlanOptions,
    /// Pieces per joint.
    out: Vec<Vec<Piece>>,
    /// Arrival time of each entry planned so far.
    arrival: Vec<f64>,
    /// Arrival of the latest rebasing entry: the origin of `at`.
    base: f64,
    /// How late the latest timed entry arrived (stretched) after its `at`.
    delay: f64,
    /// Reused buffers: the section's positions and times, and the untimed
    /// planner's.
    pos: Vec<&'a [f64]>,
    times: Vec<f64>,
    scratch: Scratch,
}

impl<'a> Sections<'a> {
    fn new(limits: &'a [JointLimits], entries: &'a [Entry<'a>], options: &'a PlanOptions) -> Self {
        Sections {
            limits,
            entries,
            options,
            out: (0..limits.len())
                .map(|_| Vec::with_capacity(entries.len() * 7))
                .collect(),
            arrival: vec![0.0; entries.len()],
            base: 0.0,
            delay: 0.0,
            pos: Vec::with_capacity(entries.len()),
            times: Vec::with_capacity(entries.len()),
            scratch: Scratch::default(),
        }
    }

    /// After the section `i..=j`: the time origin and delay the next
    /// section's `at`s count from.
    fn rebase(&mut self, i: usize, j: usize) {
        for k in i + 1..=j {
            let e = &self.entries[k];
            if e.rebase {
                self.base = self.arrival[k];
                self.delay = 0.0;
            } else if let Some(at) = e.at {
                self.delay = self.arrival[k] - (self.base + at);
            }
        }
    }

    fn finish(self) -> Trajectory {
        let last = self.entries.len() - 1;
        let arrival = &self.arrival;
        let segments = (1..self.entries.len())
            .map(|k| SegmentTiming {
                keyframe: self.entries[k].index,
                cycle: self.entries[k].cycle,
                start: arrival[k - 1],
                end: arrival[k],
            })
            .collect();
        Trajectory::from_joints(self.out, self.entries[last].pos, arrival[last], segments)
    }
}
