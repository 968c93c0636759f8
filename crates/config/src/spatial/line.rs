//! `path: line`: the tool goes to a keyframe's `tool:` pose in a straight
//! line, its orientation slerped, at the keyframe's own speed limits; the
//! line is sampled into timed joint keyframes dense enough that the
//! planned path keeps the tool within the tolerance of the line.

use servobus_kinematics::{sample_line, ArmIk, Held, LineOptions, PoseLine};
use servobus_trajectory::{self as traj, JointState};

use super::{Context, MoveLimits, TimeLaw};
use crate::error::ConfigError;
use crate::limits::Rounded;
use crate::locate::FieldPath;
use crate::motion::Keyframe;
use crate::tool::{ik_reason, ToolPose, TOOL_FRAME};

/// Default distance the tool may stray from a line, mm.
pub(crate) const DEFAULT_TOLERANCE_MM: f64 = 0.2;

/// The range of a line's `tolerance`, mm: finer than a servo's tick at
/// the end of an arm (about 0.1 mm) is never needed, and ten centimetres
/// is no longer a line.
const MIN_TOLERANCE_MM: f64 = 0.01;
const MAX_TOLERANCE_MM: f64 = 100.0;

/// How many times the sampling is made twice as dense when the planned
/// path strays too far from the line.
const REFINEMENTS: usize = 4;

/// How often the planned path is checked against the line, s.
const CHECK_STEP_S: f64 = 0.002;

impl Context<'_> {
    /// Appends the keyframes of a straight tool move from the last of
    /// `keyframes` to `tool` (keyframe `index` at `kp`, its `at` if
    /// timed), and sets `current` (the motion's units) to its end.
    ///
    /// # Errors
    /// At the keyframe: no geometry or `tool` frame, bad limits, a line
    /// that leaves the arm's reach, needs a joint past a limit, passes near
    /// a singular pose or cannot keep to the tolerance within the joints'
    /// speed limits.
    #[allow(clippy::too_many_arguments)]
    pub fn line(
        &self,
        kp: &FieldPath,
        index: usize,
        tool: &ToolPose,
        at: Option<f64>,
        limits: &MoveLimits,
        current: &mut Vec<f64>,
        keyframes: &mut Vec<Keyframe>,
    ) -> Result<(), ConfigError> {
        let fail = |why: String| {
            self.src
                .error(&kp.key("tool"), format!("keyframe {index}: {why}"))
        };
        let tolerance = self.line_tolerance(kp, limits)?;
        let arm = self.arm(&fail)?;
        let start_q = self.radians(current);
        let chain: Vec<f64> = arm.joints().iter().map(|&j| start_q[j]).collect();
        // The end: the tool pose solved from the start, as a joint move
        // would reach it.
        let mut end = current.clone();
        crate::tool::resolve(self.robot, self.units, tool, &mut end).map_err(fail)?;
        let end_q = self.radians(&end);
        let end_chain: Vec<f64> = arm.joints().iter().map(|&j| end_q[j]).collect();
        let line = PoseLine::new(arm.frame_pose(&chain), arm.frame_pose(&end_chain));
        // The pitch always follows the slerp (without it a 5-DOF arm's
        // answers may wander along its redundancy from sample to sample);
        // the roll when the keyframe gives one.
        let held = Held {
            pitch: true,
            roll: tool.roll.is_some(),
        };
        let t0 = self.arrival(keyframes)?;
        let law = TimeLaw::new(line.extent_mm(), limits, at.map(|a| a - t0)).map_err(fail)?;
        let mut options = LineOptions {
            tolerance_mm: tolerance,
            ..LineOptions::default()
        };
        // The first sampling's samples, before any is made; the sampling
        // itself stops at what the motion has room for.
        let first = (law.duration() / options.max_step_s).ceil() + 1.0;
        self.check_samples(&kp.key("tool"), index, "this line", first, keyframes.len())?;
        options.max_samples = self.samples_left(keyframes.len());
        let tool_line = ToolLine {
            arm,
            line,
            held,
            start_q,
            chain,
            law,
        };
        for _ in 0..REFINEMENTS {
            let (poses, path) = tool_line.poses(self, &options, &fail)?;
            if worst_deviation(&tool_line.arm, &tool_line.line, &path) <= tolerance {
                self.push_samples(
                    kp,
                    t0,
                    poses.iter().map(|(t, q)| (*t, q.as_slice())),
                    keyframes,
                );
                if let Some((_, q)) = poses.last() {
                    *current = q.iter().map(|&v| self.units.from_rad(v)).collect();
                }
                return Ok(());
            }
            options.max_step_s *= 0.5;
            options.tolerance_mm *= 0.5;
        }
        Err(fail(format!(
            "the planned path strays more than the tolerance {tolerance} mm from the line; \
             raise `tolerance` or lower `max_speed`"
        )))
    }

    /// A line keyframe's `tolerance` (at `kp`), checked, or the default.
    fn line_tolerance(&self, kp: &FieldPath, limits: &MoveLimits) -> Result<f64, ConfigError> {
        let tolerance = limits.tolerance.unwrap_or(DEFAULT_TOLERANCE_MM);
        if !(MIN_TOLERANCE_MM..=MAX_TOLERANCE_MM).contains(&tolerance) {
            return Err(self.src.error(
                &kp.key("tolerance"),
                format!(
                    "must be a distance from {MIN_TOLERANCE_MM} to {MAX_TOLERANCE_MM} mm, got {}",
                    Rounded(tolerance)
                ),
            ));
        }
        Ok(tolerance)
    }

    /// The robot's arm up to its `tool` frame; `fail` says why there is none.
    fn arm(&self, fail: &impl Fn(String) -> ConfigError) -> Result<ArmIk, ConfigError> {
        let model = self.geometry(fail)?;
        ArmIk::new(&model, TOOL_FRAME).map_err(|e| fail(e.to_string()))
    }
}

/// Whole robot poses over a move: `(t, every joint in radians)`.
type RobotPoses = Vec<(f64, Vec<f64>)>;

/// A straight tool move to sample: the arm, the line, its time law and the
/// joints at its start.
struct ToolLine {
    arm: ArmIk,
    line: PoseLine,
    held: Held,
    /// Every joint of the robot at the start, radians.
    start_q: Vec<f64>,
    /// The arm's joints at the start, radians.
    chain: Vec<f64>,
    law: TimeLaw,
}

impl ToolLine {
    /// Samples the line under `options` into whole robot poses (`(t, every
    /// joint in radians)`) and plans them as the motion will.
    ///
    /// # Errors
    /// Through `fail`: a line the arm cannot follow, or joints that cannot
    /// follow it within their limits.
    fn poses(
        &self,
        ctx: &Context<'_>,
        options: &LineOptions,
        fail: &impl Fn(String) -> ConfigError,
    ) -> Result<(RobotPoses, traj::Trajectory), ConfigError> {
        let law = &self.law;
        let plan = sample_line(
            &self.arm,
            &self.line,
            self.held,
            &self.chain,
            law.duration(),
            |t| law.s_of_t(t),
            options,
        )
        .map_err(|e| {
            fail(format!(
                "the line from the previous keyframe cannot be followed {:.1} mm along: {}",
                e.along_mm,
                ik_reason(&e.reason, ctx.units)
            ))
        })?;
        // Whole robot poses: joints off the arm keep their values.
        let poses: RobotPoses = plan
            .samples
            .iter()
            .map(|s| {
                let mut q = self.start_q.clone();
                for (k, &j) in self.arm.joints().iter().enumerate() {
                    q[j] = s.q[k];
                }
                (s.t, q)
            })
            .collect();
        let path = ctx
            .plan_samples(poses.iter().map(|(t, q)| (*t, q.as_slice())))
            .map_err(|e| {
                fail(format!(
                    "the joints cannot follow the line at this speed ({e}); lower \
                     `max_speed` or `max_acceleration`"
                ))
            })?;
        Ok((poses, path))
    }
}

/// The farthest the planned `path` takes the tool from `line`, mm.
fn worst_deviation(arm: &ArmIk, line: &PoseLine, path: &traj::Trajectory) -> f64 {
    let mut state = vec![JointState::default(); path.joints()];
    let mut chain = vec![0.0; arm.joints().len()];
    let steps = (path.duration() / CHECK_STEP_S).ceil() as usize;
    let mut worst: f64 = 0.0;
    for k in 0..=steps {
        let t = (k as f64 * CHECK_STEP_S).min(path.duration());
        path.sample(t, &mut state);
        for (c, &j) in chain.iter_mut().zip(arm.joints()) {
            *c = state[j].position;
        }
        let p = arm.frame_pose(&chain).translation.vector;
        worst = worst.max(line.distance_mm(&p.into()));
    }
    worst
}
