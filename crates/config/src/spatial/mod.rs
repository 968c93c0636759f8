//! Motion in space: the keyframe fields that move the robot through space
//! rather than joint by joint, turned into dense timed joint keyframes when
//! the motion loads, so that the planner and the limits check them as
//! usual.
//!
//! - `path: line` on a keyframe with a `tool:`: the tool goes there in a
//!   straight line (line.rs).
//! - `walk:`: a hexapod walks (legs.rs).
//! - `body:`: a hexapod's body moves with its feet planted (legs.rs).
//!
//! Every keyframe made here carries the line and column of the file's
//! keyframe, so errors of the planner point at it.

mod legs;
mod line;
mod summary;

use serde::Deserialize;
use servobus_trajectory::{self as traj, JointLimits, JointState, PlanOptions, Trajectory};

use super::error::{ConfigError, Source};
use super::limits::{check_samples, samples_left};
use super::locate::FieldPath;
use super::motion::{Interpolation, Keyframe, Motion, OnLimit};
use super::plan_terms::{keyframe_of, plan_reason};
use super::robot::Robot;
use super::trajectory::{joint_limits, plan_options, SAMPLE_SHAPE};
use super::Units;

pub(super) use legs::{RawBody, RawWalk};
pub use summary::{spatial_summary, FeetSummary, SpatialSummary, ToolSummary};

/// How the tool gets to a keyframe's `tool:` pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
#[serde(expecting = "`line` or `joint`")]
pub(super) enum PathKind {
    /// Straight, in space.
    Line,
    /// Joint by joint (the default).
    Joint,
}

/// The speed limits of a straight tool move or a body move, as a keyframe
/// gives them (mm/s, mm/s^2, mm/s^3), and a line's tolerance (mm).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct MoveLimits {
    pub max_speed: Option<f64>,
    pub max_acceleration: Option<f64>,
    pub max_jerk: Option<f64>,
    pub tolerance: Option<f64>,
}

/// Defaults of a move's limits: 100 mm/s, 400 mm/s^2, and ten times the
/// acceleration per second of jerk (the acceleration builds up in 0.1 s).
const DEFAULT_SPEED: f64 = 100.0;
const DEFAULT_ACCELERATION: f64 = 400.0;
const JERK_PER_ACCELERATION: f64 = 10.0;

/// What the spatial keyframes need of the motion being loaded.
pub(super) struct Context<'a> {
    pub src: &'a Source,
    pub robot: &'a Robot,
    pub units: Units,
    pub interpolation: Interpolation,
    pub on_limit: OnLimit,
    /// Where the body's moves count from (`body:` keyframes in a row).
    pub body: Option<legs::BodyState>,
    /// How many times the motion repeats: the samples a keyframe makes are
    /// planned that many times.
    pub repeat: u64,
}

/// The time law of a move of `extent` (mm) under `limits`, ending at
/// `duration` s after its start when given: the fraction covered at time
/// `t` (`s_of_t`) and its duration.
pub(super) struct TimeLaw {
    path: Trajectory,
    extent: f64,
}

/// The longest move in space (a line, a body pose or a whole walk), s:
/// each is sampled densely, so its length bounds the memory it takes.
pub(crate) const MAX_SPATIAL_S: f64 = 3600.0;

impl TimeLaw {
    /// Plans the move, as one joint from 0 to `extent` and back to rest.
    ///
    /// # Errors
    /// The reason as text: limits that are not positive, or a `duration`
    /// too short for them.
    pub fn new(extent: f64, limits: &MoveLimits, duration: Option<f64>) -> Result<Self, String> {
        let v = limits.max_speed.unwrap_or(DEFAULT_SPEED);
        let a = limits.max_acceleration.unwrap_or(DEFAULT_ACCELERATION);
        let j = limits.max_jerk.unwrap_or(a * JERK_PER_ACCELERATION);
        for (name, x) in [("max_speed", v), ("max_acceleration", a), ("max_jerk", j)] {
            if !(x.is_finite() && x > 0.0) {
                return Err(format!("`{name}` must be a positive number, got {x}"));
            }
        }
        let extent = extent.max(1e-9);
        let lim = [JointLimits::new(v, a, Some(j)).with_positions(0.0, extent)];
        let end = traj::Keyframe::new([extent]);
        let end = match duration {
            Some(d) => end.at(d),
            None => end,
        };
        let path = traj::plan(
            &lim,
            &[traj::Keyframe::new([0.0]), end],
            &PlanOptions::default(),
        )
        .map_err(|e| match e {
            traj::PlanError::TooSoon { needed, .. } => format!(
                "at these speeds the move takes at least {needed:.3} s, more than `at` leaves"
            ),
            e => e.to_string(),
        })?;
        // A move is sampled every few ms: an hour bounds the samples (and
        // the memory) whatever the file says.
        if path.duration() > MAX_SPATIAL_S {
            return Err(format!(
                "the move would take {:.0} s: a move in space may take {MAX_SPATIAL_S} s at most",
                path.duration()
            ));
        }
        Ok(TimeLaw { path, extent })
    }

    /// The move's duration, s.
    pub fn duration(&self) -> f64 {
        self.path.duration()
    }

    /// The fraction of the move covered at `t` s.
    pub fn s_of_t(&self, t: f64) -> f64 {
        let mut out = [JointState::default()];
        self.path.sample(t, &mut out);
        (out[0].position / self.extent).clamp(0.0, 1.0)
    }
}

impl Context<'_> {
    /// When the motion so far (`keyframes`, one repetition) arrives at its
    /// last keyframe, s from the start; that keyframe is made timed (at
    /// that arrival) so that the samples after it keep their times.
    ///
    /// # Errors
    /// The planner's error about the motion so far, located in the file.
    pub fn arrival(&self, keyframes: &mut [Keyframe]) -> Result<f64, ConfigError> {
        let Some(last) = keyframes.last() else {
            return Ok(0.0);
        };
        if let Some(at) = last.at {
            return Ok(at);
        }
        if keyframes.len() == 1 {
            // The start.
            return Ok(0.0);
        }
        let so_far = Motion {
            path: self.src.path.clone(),
            robot_path: std::path::PathBuf::new(),
            units: self.units,
            rate_hz: None,
            joints: self.robot.joints().map(|j| j.name.clone()).collect(),
            keyframes: keyframes.to_vec(),
            repeat: 1,
            on_limit: self.on_limit,
            interpolation: self.interpolation,
        };
        let path = super::trajectory::plan_motion(&so_far, self.robot)?;
        // A hair later than the fastest arrival, so that planning the whole
        // motion finds the time enough.
        let at = path.duration() + 1e-6;
        if let Some(last) = keyframes.last_mut() {
            last.at = Some(at);
            last.planned_at = true;
        }
        Ok(at)
    }

    /// Appends joint keyframes (radians, robot order) at times `t0 + t`
    /// (skipping the first sample, which is the keyframe before), all at
    /// the file keyframe `kp`'s line and column.
    pub fn push_samples<'s>(
        &self,
        kp: &FieldPath,
        t0: f64,
        samples: impl Iterator<Item = (f64, &'s [f64])>,
        keyframes: &mut Vec<Keyframe>,
    ) {
        let (line, column) = self.src.position(kp);
        for (t, q) in samples.skip(1) {
            keyframes.push(Keyframe {
                at: Some(t0 + t),
                planned_at: true,
                pose: None,
                tool: false,
                positions: q.iter().map(|&v| self.units.from_rad(v)).collect(),
                grasps: Vec::new(),
                line,
                column,
            });
        }
    }

    /// Plans a spatial keyframe's samples (`(t, every joint in radians)`,
    /// the first the keyframe before) on their own, as the whole motion
    /// will plan them: a sample path beyond a joint's limits is refused
    /// here, with a reason about the move, rather than stretched (which
    /// would break the move's geometry).
    ///
    /// # Errors
    /// The planner's reason in the file's terms (joints by name, angles in
    /// the motion's units, the time into the move).
    pub fn plan_samples<'s>(
        &self,
        samples: impl Iterator<Item = (f64, &'s [f64])>,
    ) -> Result<Trajectory, String> {
        let mut times = Vec::new();
        let keys: Vec<traj::Keyframe> = samples
            .enumerate()
            .map(|(k, (t, q))| {
                times.push(t);
                let kf = traj::Keyframe::new(q.to_vec()).at(t);
                if k == 0 {
                    kf
                } else {
                    kf.shape(SAMPLE_SHAPE)
                }
            })
            .collect();
        let options = plan_options(self.interpolation, OnLimit::Error, 1);
        traj::plan(&joint_limits(self.robot), &keys, &options).map_err(|e| {
            let joints: Vec<String> = self.robot.joints().map(|j| j.name.clone()).collect();
            let reason = plan_reason(&e, &joints, self.units);
            match keyframe_of(&e).and_then(|k| times.get(k)) {
                Some(t) => format!("{reason}, {t:.2} s into the move"),
                None => reason,
            }
        })
    }

    /// Refuses, at `field`, a generator that would make `samples` whole
    /// robot poses (keyframes) after the `keyframes` the motion has so far,
    /// more than [`MAX_PLANNED_SEGMENTS`](crate::limits::MAX_PLANNED_SEGMENTS)
    /// leaves room for: checked before the samples are allocated.
    ///
    /// # Errors
    /// [`ConfigError`] at `field`, `keyframe {index}: ...` with the limit.
    pub fn check_samples(
        &self,
        field: &FieldPath,
        index: usize,
        what: &str,
        samples: f64,
        keyframes: usize,
    ) -> Result<(), ConfigError> {
        let joints = self.robot.joint_count();
        check_samples(samples, keyframes, self.repeat, joints).map_err(|e| {
            self.src
                .error(field, format!("keyframe {index}: {what} {e}; shorten it"))
        })
    }

    /// How many samples a generator may still make after `keyframes`.
    pub fn samples_left(&self, keyframes: usize) -> usize {
        samples_left(keyframes, self.repeat, self.robot.joint_count())
    }

    /// The robot's geometry; `fail` turns the reason there is none into
    /// the error.
    fn geometry(
        &self,
        fail: &impl Fn(String) -> ConfigError,
    ) -> Result<servobus_kinematics::Geometry, ConfigError> {
        self.robot.geometry().ok_or_else(|| {
            fail(format!(
                "robot `{}` has no `kinematics:` section",
                self.robot.name
            ))
        })
    }

    /// The joints of `current` (the motion's units) in radians.
    pub fn radians(&self, current: &[f64]) -> Vec<f64> {
        current.iter().map(|&v| self.units.to_rad(v)).collect()
    }
}
