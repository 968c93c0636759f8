//! `walk:` and `body:` keyframes of a legged robot: a gait along segments
//! of body velocity, and body poses with the feet planted, each sampled
//! into timed joint keyframes with every leg solved in closed form.

use serde::Deserialize;
use servobus_kinematics::{
    plan_walk, Gait, Isometry3, Legs, Point3, PoseLine, Poses, UnitQuaternion, Vector3, Walk,
    WalkSegment,
};

use super::{Context, MoveLimits, TimeLaw};
use crate::error::ConfigError;
use crate::limits::{Rounded, MAX_WALK_SEGMENTS, MIN_STEP_PERIOD_S};
use crate::locate::FieldPath;
use crate::motion::Keyframe;
use crate::tool::ik_reason;

/// Joint samples of walks and body moves come this far apart at most, s.
pub(crate) const LEG_STEP_S: f64 = 0.02;

/// A keyframe's `walk:`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawWalk {
    gait: RawGait,
    #[serde(default)]
    stride: Option<f64>,
    lift: f64,
    period: f64,
    segments: Vec<RawSegment>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
#[serde(expecting = "`tripod`, `ripple` or `wave`")]
enum RawGait {
    Tripod,
    Ripple,
    Wave,
}

/// One segment of a walk: `{velocity: [vx, vy], turn, duration}`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSegment {
    #[serde(default)]
    velocity: [f64; 2],
    #[serde(default)]
    turn: f64,
    duration: f64,
}

/// A keyframe's `body:`: the body's height above the ground, its shift and
/// its roll, pitch and yaw, the feet planted.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBody {
    #[serde(default)]
    height: Option<f64>,
    #[serde(default)]
    shift: Option<[f64; 2]>,
    #[serde(default)]
    roll: Option<f64>,
    #[serde(default)]
    pitch: Option<f64>,
    #[serde(default)]
    yaw: Option<f64>,
}

/// Where a run of `body:` keyframes counts from: the feet (in the body's
/// frame before the first of them, which is the ground's frame), the
/// body's height then, and its pose now.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct BodyState {
    feet: Vec<Point3<f64>>,
    height: f64,
    pose: Isometry3<f64>,
}

impl Context<'_> {
    /// The robot's six legs; `fail` turns the reason they cannot be solved into the error.
    fn legs(&self, fail: &impl Fn(String) -> ConfigError) -> Result<Legs, ConfigError> {
        let model = self.geometry(fail)?;
        Legs::new(&model).map_err(|e| fail(e.to_string()))
    }

    /// Appends the keyframes of a walk from the last of `keyframes`, and
    /// sets `current` to where it ends.
    ///
    /// # Errors
    /// At the keyframe's `walk`: numbers out of range, not six legs, a
    /// stride too short for a segment, a foot a leg cannot reach.
    pub fn walk(
        &mut self,
        kp: &FieldPath,
        index: usize,
        raw: &RawWalk,
        current: &mut Vec<f64>,
        keyframes: &mut Vec<Keyframe>,
    ) -> Result<(), ConfigError> {
        let wp = kp.key("walk");
        let fail = |why: String| self.src.error(&wp, format!("keyframe {index}: {why}"));
        self.check_walk(&wp, raw)?;
        let segments = self.walk_segments(&wp, raw)?;
        let total: f64 = segments.iter().map(|s| s.duration_s).sum();
        if total > super::MAX_SPATIAL_S {
            return Err(fail(format!(
                "the walk's segments take {total:.0} s: a walk may take {} s at most",
                super::MAX_SPATIAL_S
            )));
        }
        // The walk ends at most two periods after its segments (the body
        // stops within one, the last swing lands within the next): its
        // samples, checked before any is made.
        let samples = ((total + 2.0 * raw.period) / LEG_STEP_S).ceil() + 1.0;
        self.check_samples(&wp, index, "this walk", samples, keyframes.len())?;
        let legs = self.legs(&fail)?;
        let walk = Walk {
            gait: raw.gait.gait(),
            stride_mm: raw.stride,
            lift_mm: raw.lift,
            period_s: raw.period,
            segments,
            step_s: LEG_STEP_S,
        };
        let start = self.radians(current);
        let plan = plan_walk(&legs, &walk, &start).map_err(|e| fail(e.to_string()))?;
        self.plan_samples(plan.samples.iter().map(|s| (s.t, s.q.as_slice())))
            .map_err(|e| {
                fail(format!(
                    "the legs cannot keep this gait within their limits ({e}); lengthen \
                     `period`, lower `lift` or slow the segments down"
                ))
            })?;
        let t0 = self.arrival(keyframes)?;
        self.push_samples(
            kp,
            t0,
            plan.samples.iter().map(|s| (s.t, s.q.as_slice())),
            keyframes,
        );
        if let Some(last) = plan.samples.last() {
            *current = last.q.iter().map(|&v| self.units.from_rad(v)).collect();
        }
        self.body = None;
        Ok(())
    }

    /// Checks a walk's (at `wp`) period, lift, stride and number of segments.
    fn check_walk(&self, wp: &FieldPath, raw: &RawWalk) -> Result<(), ConfigError> {
        let period_ok = (MIN_STEP_PERIOD_S..=super::MAX_SPATIAL_S).contains(&raw.period);
        if !period_ok {
            return Err(self.src.error(
                &wp.key("period"),
                format!(
                    "must be a step period from {MIN_STEP_PERIOD_S} to {} s, got {}",
                    super::MAX_SPATIAL_S,
                    Rounded(raw.period)
                ),
            ));
        }
        if !(raw.lift.is_finite() && raw.lift >= 0.0) {
            return Err(self.src.error(
                &wp.key("lift"),
                format!("must be a height >= 0 mm, got {}", raw.lift),
            ));
        }
        if let Some(stride) = raw.stride.filter(|&v| !positive_spatial(v)) {
            return Err(self.src.error(
                &wp.key("stride"),
                format!(
                    "must be a positive number up to {}, got {stride}",
                    super::MAX_SPATIAL_S
                ),
            ));
        }
        if raw.segments.is_empty() {
            return Err(self
                .src
                .error(&wp.key("segments"), "a walk needs at least one segment"));
        }
        if raw.segments.len() > MAX_WALK_SEGMENTS {
            return Err(self.src.error(
                &wp.key("segments"),
                format!(
                    "{} segments: a walk may have 1 to {MAX_WALK_SEGMENTS}",
                    raw.segments.len()
                ),
            ));
        }
        Ok(())
    }

    /// The segments of a walk (at `wp`), checked: a duration in range,
    /// finite velocity and turn.
    fn walk_segments(
        &self,
        wp: &FieldPath,
        raw: &RawWalk,
    ) -> Result<Vec<WalkSegment>, ConfigError> {
        let mut segments = Vec::with_capacity(raw.segments.len());
        for (k, s) in raw.segments.iter().enumerate() {
            let sp = wp.key("segments").index(k);
            if !positive_spatial(s.duration) {
                return Err(self.src.error(
                    &sp.key("duration"),
                    format!(
                        "must be a time above 0 and up to {} s, got {}",
                        super::MAX_SPATIAL_S,
                        Rounded(s.duration)
                    ),
                ));
            }
            if !(s.velocity.iter().all(|v| v.is_finite()) && s.turn.is_finite()) {
                return Err(self
                    .src
                    .error(&sp, "velocity and turn must be finite numbers"));
            }
            segments.push(WalkSegment {
                velocity_mm_s: s.velocity,
                turn_rad_s: self.units.to_rad(s.turn),
                duration_s: s.duration,
            });
        }
        Ok(segments)
    }

    /// Appends the keyframes of a body move, the feet planted, from the
    /// last of `keyframes` (or the body pose of the `body:` keyframe before
    /// it) to `raw`, and sets `current` to its end.
    ///
    /// # Errors
    /// At the keyframe's `body`: numbers that are not finite, bad limits,
    /// a foot a leg cannot reach from the new pose.
    #[allow(clippy::too_many_arguments)]
    pub fn body(
        &mut self,
        kp: &FieldPath,
        index: usize,
        raw: &RawBody,
        at: Option<f64>,
        limits: &MoveLimits,
        current: &mut Vec<f64>,
        keyframes: &mut Vec<Keyframe>,
    ) -> Result<(), ConfigError> {
        let bp = kp.key("body");
        let src = self.src;
        let fail = |why: String| src.error(&bp, format!("keyframe {index}: {why}"));
        self.check_body(&bp, index, raw)?;
        let legs = self.legs(&fail)?;
        let start = self.radians(current);
        let state = match self.body.take() {
            Some(s) => s,
            None => BodyState::standing(&legs, &start),
        };
        let to = self.body_target(raw, &state);
        let line = PoseLine::new(state.pose, to);
        let t0 = self.arrival(keyframes)?;
        let law = TimeLaw::new(line.extent_mm(), limits, at.map(|a| a - t0)).map_err(fail)?;
        let count = (law.duration() / LEG_STEP_S).ceil() + 1.0;
        self.check_samples(&bp, index, "this body move", count, keyframes.len())?;
        let samples = legs
            .body_move(
                &line,
                &state.feet,
                &start,
                law.duration(),
                |t| law.s_of_t(t),
                LEG_STEP_S,
            )
            .map_err(|e| {
                fail(format!(
                    "at {:.2} s into the move, leg `{}`: {}",
                    e.t,
                    e.leg,
                    ik_reason(&e.reason, self.units)
                ))
            })?;
        self.plan_samples(samples.iter().map(|s| (s.t, s.q.as_slice())))
            .map_err(|e| {
                fail(format!(
                    "the legs cannot follow this body move within their limits ({e}); lower \
                     `max_speed` or `max_acceleration`"
                ))
            })?;
        self.push_samples(
            kp,
            t0,
            samples.iter().map(|s| (s.t, s.q.as_slice())),
            keyframes,
        );
        if let Some(last) = samples.last() {
            *current = last.q.iter().map(|&v| self.units.from_rad(v)).collect();
        }
        self.body = Some(BodyState { pose: to, ..state });
        Ok(())
    }

    /// Checks a body move's (at `bp`) numbers: finite, and a height above
    /// the ground.
    fn check_body(&self, bp: &FieldPath, index: usize, raw: &RawBody) -> Result<(), ConfigError> {
        let numbers = raw
            .height
            .iter()
            .chain(raw.shift.iter().flatten())
            .chain(&raw.roll)
            .chain(&raw.pitch)
            .chain(&raw.yaw);
        if !numbers.into_iter().all(|v| v.is_finite()) {
            return Err(self.src.error(
                bp,
                format!(
                    "keyframe {index}: height, shift, roll, pitch and yaw must be finite numbers"
                ),
            ));
        }
        if let Some(height) = raw.height {
            if height <= 0.0 {
                return Err(self.src.error(
                    &bp.key("height"),
                    format!(
                        "keyframe {index}: must be a height above the ground, > 0 mm, got {}",
                        Rounded(height)
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The body pose `raw` asks for, relative to the ground under `state`:
    /// its shift, its height as a lift from `state`'s, its roll, pitch and yaw.
    fn body_target(&self, raw: &RawBody, state: &BodyState) -> Isometry3<f64> {
        let shift = raw.shift.unwrap_or([0.0, 0.0]);
        let lift = raw.height.map_or(0.0, |h| h - state.height);
        let angle = |a: Option<f64>| self.units.to_rad(a.unwrap_or(0.0));
        Isometry3::from_parts(
            Vector3::new(shift[0], shift[1], lift).into(),
            UnitQuaternion::from_euler_angles(angle(raw.roll), angle(raw.pitch), angle(raw.yaw)),
        )
    }
}

/// Whether `v` is a positive number of at most [`super::MAX_SPATIAL_S`].
fn positive_spatial(v: f64) -> bool {
    v.is_finite() && v > 0.0 && v <= super::MAX_SPATIAL_S
}

impl RawGait {
    /// The gait it names.
    fn gait(self) -> Gait {
        match self {
            RawGait::Tripod => Gait::Tripod,
            RawGait::Ripple => Gait::Ripple,
            RawGait::Wave => Gait::Wave,
        }
    }
}

impl BodyState {
    /// The start of a run of body moves: `legs` at joint positions `start`
    /// (radians), the body level at its pose then.
    fn standing(legs: &Legs, start: &[f64]) -> Self {
        let mut poses = Poses::new(legs.model());
        let mut feet = vec![Point3::origin(); legs.len()];
        legs.feet(start, &mut poses, &mut feet);
        let height = -feet.iter().map(|p| p.z).sum::<f64>() / feet.len() as f64;
        BodyState {
            feet,
            height,
            pose: Isometry3::identity(),
        }
    }
}
