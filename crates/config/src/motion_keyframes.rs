//! A motion file's keyframes as written, and their resolution one by one
//! into [`Keyframe`]s that hold a position for every joint of the robot.

use serde::Deserialize;

use super::error::{ConfigError, Source};
use super::limits::{check_duration, Rounded, MAX_MOTION_DURATION_S};
use super::locate::FieldPath;
use super::motion::{Keyframe, KeyframeGrasp};
use super::motion_poses::{list, PoseList, PoseRef, Resolver};
use super::robot::Robot;
use super::spatial::{Context, MoveLimits, PathKind, RawBody, RawWalk};
use super::Units;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(
    expecting = "a keyframe: a mapping with `pose:`, `tool:`, `walk:`, `body:` or `grasp:`, and optional `at:`"
)]
pub(super) struct RawKeyframe {
    #[serde(default)]
    at: Option<f64>,
    #[serde(default)]
    pose: Option<PoseRef>,
    #[serde(default)]
    tool: Option<super::tool::ToolPose>,
    #[serde(default)]
    path: Option<PathKind>,
    #[serde(default)]
    max_speed: Option<f64>,
    #[serde(default)]
    max_acceleration: Option<f64>,
    #[serde(default)]
    max_jerk: Option<f64>,
    #[serde(default)]
    tolerance: Option<f64>,
    #[serde(default)]
    walk: Option<RawWalk>,
    #[serde(default)]
    body: Option<RawBody>,
    #[serde(default)]
    grasp: Option<std::collections::BTreeMap<String, RawGrasp>>,
}

/// A keyframe's grasp of one joint.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(expecting = "a grasp: a mapping with `effort:` (percent of the servo's torque)")]
pub(super) struct RawGrasp {
    effort: f64,
}

impl RawKeyframe {
    /// The speed limits and tolerance this keyframe gives its move.
    fn limits(&self) -> MoveLimits {
        MoveLimits {
            max_speed: self.max_speed,
            max_acceleration: self.max_acceleration,
            max_jerk: self.max_jerk,
            tolerance: self.tolerance,
        }
    }
}

/// The keyframes resolved so far and what the next one starts from: the
/// joint positions, the last timed keyframe and the spatial moves' state.
pub(super) struct KeyframeBuilder<'a> {
    src: &'a Source,
    robot: &'a Robot,
    units: Units,
    poses: &'a PoseList,
    resolver: Resolver<'a>,
    spatial: Context<'a>,
    /// Position of every joint after the last keyframe, in the motion's units.
    current: Vec<f64>,
    keyframes: Vec<Keyframe>,
    /// Index and time of the last keyframe with an `at`.
    last_at: Option<(usize, f64)>,
    /// Which joints grasp after the last keyframe.
    grasping: Vec<bool>,
    /// The joints the last keyframe's pose named.
    named: Vec<usize>,
}

impl<'a> KeyframeBuilder<'a> {
    /// A builder for `count` keyframes, every joint starting at its rest
    /// position; `spatial` resolves the `walk`, `body` and line keyframes.
    pub(super) fn new(poses: &'a PoseList, spatial: Context<'a>, count: usize) -> Self {
        let (src, robot, units) = (spatial.src, spatial.robot, spatial.units);
        KeyframeBuilder {
            src,
            robot,
            units,
            poses,
            resolver: Resolver { src, robot, units },
            current: robot
                .joints()
                .map(|j| robot.units.convert(j.rest(), units))
                .collect(),
            keyframes: Vec::with_capacity(count),
            last_at: None,
            grasping: vec![false; robot.joint_count()],
            named: Vec::new(),
            spatial,
        }
    }

    /// The keyframes resolved.
    pub(super) fn finish(self) -> Vec<Keyframe> {
        self.keyframes
    }

    /// Resolves keyframe `i` (at `kp` in the file) after the ones before it.
    pub(super) fn add(
        &mut self,
        kp: &FieldPath,
        i: usize,
        rk: &RawKeyframe,
    ) -> Result<(), ConfigError> {
        if let Some(at) = rk.at {
            self.check_at(kp, i, at)?;
        }
        check_spatial(self.src, kp, i, rk)?;
        let pose_name = self.apply_pose(kp, i, rk)?;
        let grasps = self.grasps(kp, i, rk)?;
        if self.spatial_move(kp, i, rk)? {
            return Ok(());
        }
        // A tool pose moves the arm's joints there, from this pose.
        if let Some(tool) = &rk.tool {
            super::tool::resolve(self.robot, self.units, tool, &mut self.current).map_err(
                |why| {
                    self.src
                        .error(&kp.key("tool"), format!("keyframe {i}: {why}"))
                },
            )?;
        }
        let (line, column) = self.src.position(kp);
        self.keyframes.push(Keyframe {
            at: rk.at,
            planned_at: false,
            pose: pose_name,
            tool: rk.tool.is_some(),
            positions: self.current.clone(),
            grasps,
            line,
            column,
        });
        Ok(())
    }

    /// Keyframe `i`'s grasps: those its `grasp:` makes (the joint's
    /// position set to its `min`) and those its pose ends.
    fn grasps(
        &mut self,
        kp: &FieldPath,
        i: usize,
        rk: &RawKeyframe,
    ) -> Result<Vec<KeyframeGrasp>, ConfigError> {
        let mut out = Vec::new();
        for &ix in &self.named {
            if self.grasping.get(ix).copied().unwrap_or(false) {
                self.grasping[ix] = false;
                out.push(KeyframeGrasp {
                    joint: ix,
                    effort: None,
                });
            }
        }
        let Some(grasp) = &rk.grasp else {
            return Ok(out);
        };
        let field = kp.key("grasp");
        if rk.walk.is_some() || rk.body.is_some() || rk.path.is_some() {
            return Err(self.src.error(
                &field,
                format!("keyframe {i}: a grasp goes on a keyframe of joint positions, not on a move in space"),
            ));
        }
        for (name, g) in grasp {
            let at = field.key(name);
            let Some(ix) = self.robot.joint_index(name) else {
                let names: Vec<&str> = self.robot.joints().map(|j| j.name.as_str()).collect();
                return Err(self.src.key_error(
                    &at,
                    format!("no joint `{name}` in the robot (joints: {})", list(&names)),
                ));
            };
            let Some(joint) = self.robot.joints().nth(ix) else {
                continue;
            };
            let why = if joint.is_wheel() {
                Some("a wheel has nothing to close".to_owned())
            } else if !(g.effort.is_finite() && g.effort > 0.0 && g.effort <= 100.0) {
                Some(format!(
                    "the effort is a percentage of the servo's torque, above 0 and at most 100, got {}",
                    Rounded(g.effort)
                ))
            } else if self.named.contains(&ix) {
                Some("the pose gives it a position too: a grasping joint closes until it meets something".to_owned())
            } else {
                None
            };
            if let Some(why) = why {
                return Err(self.src.error(&at, format!("keyframe {i}: {name}: {why}")));
            }
            self.current[ix] = self.robot.units.convert(joint.min, self.units);
            self.grasping[ix] = true;
            out.push(KeyframeGrasp {
                joint: ix,
                effort: Some(g.effort),
            });
        }
        Ok(out)
    }

    /// Checks keyframe `i`'s time `at`: a time in range, 0 for the first
    /// keyframe, after the last timed keyframe.
    fn check_at(&mut self, kp: &FieldPath, i: usize, at: f64) -> Result<(), ConfigError> {
        let field = kp.key("at");
        if !(at.is_finite() && at >= 0.0) {
            return Err(self.src.error(
                &field,
                format!(
                    "must be a time from 0 to {MAX_MOTION_DURATION_S} s (a day), got {}",
                    Rounded(at)
                ),
            ));
        }
        if let Err(e) = check_duration(at) {
            return Err(self.src.error(&field, e.to_string()));
        }
        if i == 0 && at != 0.0 {
            return Err(self.src.error(
                &field,
                format!("the first keyframe is the start, at 0 s; got {at}"),
            ));
        }
        if let Some((j, prev)) = self.last_at {
            if at <= prev {
                return Err(self.src.error(
                    &field,
                    format!("{at} s is not after keyframe {j} at {prev} s"),
                ));
            }
        }
        self.last_at = Some((i, at));
        Ok(())
    }

    /// Sets the joints keyframe `i`'s `pose` names (a pose of the file or a
    /// map of its own), and returns the pose's name when it names one.
    fn apply_pose(
        &mut self,
        kp: &FieldPath,
        i: usize,
        rk: &RawKeyframe,
    ) -> Result<Option<String>, ConfigError> {
        let poses = self.poses;
        let (pose_name, pairs) = match &rk.pose {
            None if rk.tool.is_none()
                && rk.walk.is_none()
                && rk.body.is_none()
                && rk.grasp.is_none() =>
            {
                return Err(self.src.error(
                    kp,
                    "a keyframe needs a `pose`, `tool`, `walk`, `body` or `grasp`",
                ))
            }
            None => (None, None),
            Some(PoseRef::Name(name)) => {
                let Some((_, pose)) = poses.0.iter().find(|(n, _)| n == name) else {
                    let known: Vec<&str> = poses.0.iter().map(|(n, _)| n.as_str()).collect();
                    return Err(self.src.error(
                        &kp.key("pose"),
                        format!("unknown pose `{name}` (poses: {})", list(&known)),
                    ));
                };
                (Some(name.clone()), Some(pose))
            }
            Some(PoseRef::Map(map)) => {
                self.resolver.check_pose(map, &kp.key("pose"), Some(i))?;
                (None, Some(map))
            }
        };
        self.named.clear();
        for (joint, value) in pairs.iter().flat_map(|p| &p.0) {
            if let Some(ix) = self.robot.joint_index(joint) {
                self.current[ix] = *value;
                self.named.push(ix);
            }
        }
        Ok(pose_name)
    }

    /// Resolves keyframe `i` when it is a `walk`, a `body` move or a
    /// straight tool move, returning whether it was one. Any other keyframe
    /// ends a run of body moves.
    fn spatial_move(
        &mut self,
        kp: &FieldPath,
        i: usize,
        rk: &RawKeyframe,
    ) -> Result<bool, ConfigError> {
        let (spatial, current, keyframes) =
            (&mut self.spatial, &mut self.current, &mut self.keyframes);
        match (&rk.walk, &rk.body, &rk.tool, rk.path) {
            (Some(walk), ..) => spatial.walk(kp, i, walk, current, keyframes)?,
            (_, Some(body), ..) => {
                spatial.body(kp, i, body, rk.at, &rk.limits(), current, keyframes)?;
            }
            (_, _, Some(tool), Some(PathKind::Line)) => {
                spatial.line(kp, i, tool, rk.at, &rk.limits(), current, keyframes)?;
                spatial.body = None;
            }
            _ => {
                spatial.body = None;
                return Ok(false);
            }
        }
        Ok(true)
    }
}

/// Refuses spatial fields where they mean nothing: a first keyframe that
/// is not a pose (`walk`, `body`, `path: line` start from one), `walk` or
/// `body` with other targets, `path: line` without a `tool`, speed limits
/// without a line or body move.
fn check_spatial(
    src: &Source,
    kp: &FieldPath,
    i: usize,
    rk: &RawKeyframe,
) -> Result<(), ConfigError> {
    let line = rk.path == Some(PathKind::Line);
    let moves = rk.walk.is_some() || rk.body.is_some() || line;
    let why = if i == 0 && moves {
        Some(
            "the first keyframe is the start: give it a `pose` (walk, body and line start from it)",
        )
    } else if (rk.walk.is_some() || rk.body.is_some()) && (rk.pose.is_some() || rk.tool.is_some()) {
        Some("`walk` and `body` keyframes take no `pose` or `tool`")
    } else if rk.walk.is_some() && (rk.body.is_some() || rk.at.is_some()) {
        Some("a `walk` takes its time from its segments: no `body` or `at` with it")
    } else if line && (rk.tool.is_none() || rk.pose.is_some()) {
        Some("`path: line` needs a `tool` pose and no `pose`")
    } else if !(line || rk.body.is_some())
        && (rk.max_speed.is_some() || rk.max_acceleration.is_some() || rk.max_jerk.is_some())
    {
        Some("`max_speed`, `max_acceleration` and `max_jerk` belong to `path: line` or `body`")
    } else if !line && rk.tolerance.is_some() {
        Some("`tolerance` belongs to `path: line`")
    } else {
        None
    };
    match why {
        Some(why) => Err(src.error(kp, format!("keyframe {i}: {why}"))),
        None => Ok(()),
    }
}
