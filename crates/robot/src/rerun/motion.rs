//! What a recording logs as the robot moves: each joint's series and
//! transform, the body's pose in the world, the tool's and the feet's
//! paths, and the run's events.

use servobus_config::Robot;
use servobus_kinematics::{Geometry, Isometry3, Point3, Poses, FOOT_PREFIX};
use servobus_runtime::{CycleSample, Telemetry};

use ::rerun::{EntityPath, LineStrips3D, Points3D, Quaternion, Scalars, Transform3D};

use super::scene::{path, Paths, GHOST, ROBOT};
use super::tree::{mm_to_m, to_rerun, Tree};
use super::world::{Odometer, Trace, MEASURED_ON_GROUND_MM, PLANNED_ON_GROUND_MM};
use super::{Level, Recorder, MIN_PERIOD_S};

/// The named frame of an arm's tool.
const TOOL: &str = "tool";

/// One joint's series.
#[derive(Debug, Clone)]
pub(super) struct Series {
    pub(super) name: String,
    /// A wheel: its values are speeds, and it draws at angle 0.
    pub(super) wheel: bool,
    commanded: EntityPath,
    measured: EntityPath,
    error: EntityPath,
    pub(super) margin: EntityPath,
    temperature: EntityPath,
    current: EntityPath,
    /// Its limits, rad (`None` for a wheel).
    pub(super) limits: Option<(f64, f64)>,
}

impl Series {
    /// The series of every joint of `robot`, in its order.
    pub(super) fn of(robot: &Robot) -> Vec<Series> {
        robot
            .joints()
            .map(|j| {
                let at = |what: &str| path("joints", [j.name.as_str(), what]);
                let u = robot.units;
                Series {
                    name: j.name.clone(),
                    wheel: j.is_wheel(),
                    commanded: at("commanded"),
                    measured: at("measured"),
                    error: at("error"),
                    margin: at("margin"),
                    temperature: at("temperature"),
                    current: at("current_ma"),
                    limits: (!j.is_wheel()).then(|| (u.to_rad(j.min), u.to_rad(j.max))),
                }
            })
            .collect()
    }
}

/// The robot in space: its tree, the frames whose paths are drawn, the
/// bodies' poses in the world.
pub(super) struct Space {
    pub(super) geometry: Geometry,
    pub(super) tree: Tree,
    pub(super) paths: Paths,
    poses: Poses,
    /// The named frames whose paths are drawn: the tool, the feet.
    pub(super) tracked: Vec<usize>,
    /// Whether the tracked frames are feet (the robot walks on them).
    legged: bool,
    /// Whether the ghost's bones are drawn (with its first pose).
    ghost_drawn: bool,
    /// The bodies' odometers: the robot's (measured), the ghost's.
    bodies: [Odometer; 2],
    traces: Vec<Trace>,
    trace_paths: Vec<EntityPath>,
}

impl Space {
    /// The space of a robot with `geometry`.
    pub(super) fn new(geometry: Geometry) -> Space {
        let tree = Tree::of(&geometry);
        let frames: Vec<(usize, &str)> = (0..geometry.frame_count())
            .filter_map(|k| geometry.frame_name(k).map(|n| (k, n)))
            .collect();
        let feet: Vec<usize> = frames
            .iter()
            .filter(|(_, n)| n.starts_with(FOOT_PREFIX))
            .map(|(k, _)| *k)
            .collect();
        let legged = feet.len() >= 3;
        let tracked: Vec<usize> = if legged {
            feet
        } else {
            frames
                .iter()
                .filter(|(_, n)| *n == TOOL)
                .map(|(k, _)| *k)
                .collect()
        };
        let trace_paths = tracked
            .iter()
            .map(|&k| path("paths", [geometry.frame_name(k).unwrap_or("?")]))
            .collect();
        Space {
            poses: Poses::new(&geometry),
            paths: Paths::of(&tree),
            traces: vec![Trace::default(); tracked.len()],
            bodies: [
                Odometer::new(tracked.len(), MEASURED_ON_GROUND_MM),
                Odometer::new(tracked.len(), PLANNED_ON_GROUND_MM),
            ],
            trace_paths,
            tracked,
            legged,
            ghost_drawn: false,
            tree,
            geometry,
        }
    }

    /// The robot's tree is posed by a plan: its feet stand exactly on the
    /// ground, as the ghost's do.
    pub(super) fn planned(&mut self) {
        self.bodies[0] = Odometer::new(self.tracked.len(), PLANNED_ON_GROUND_MM);
    }

    /// The tracked frames' positions at `q` (rad), in the base frame, mm.
    fn tracked_at(&mut self, q: &[f64]) -> Vec<Point3<f64>> {
        self.geometry.forward(q, &mut self.poses);
        self.tracked
            .iter()
            .map(|&k| {
                self.poses
                    .frame(k)
                    .map_or_else(Point3::origin, |p| Point3::from(p.translation.vector))
            })
            .collect()
    }
}

/// A pose as Rerun's transform.
fn transform(pose: &Isometry3<f64>) -> Transform3D {
    let (t, q) = to_rerun(pose);
    Transform3D::from_translation_rotation(t, Quaternion::from_xyzw(q))
}

impl Recorder {
    /// A cycle's sample: the state of its joints, and (once per
    /// [`MIN_PERIOD_S`] per bus) their series, transforms and, with the
    /// first bus, the bodies and paths.
    pub(super) fn cycle(&mut self, sample: &CycleSample) {
        for j in sample.joints() {
            if let Some(slot) = self.commanded.get_mut(j.joint) {
                *slot = Some(j.commanded);
            }
            if let (Some(slot), Some(m)) = (self.measured.get_mut(j.joint), j.measured) {
                *slot = Some(m);
            }
        }
        let Some(last) = self.last.get_mut(sample.bus) else {
            return;
        };
        if sample.time_s < *last + MIN_PERIOD_S {
            return;
        }
        *last = sample.time_s;
        self.set_time(sample.time_s);
        for j in sample.joints() {
            let Some(series) = self.joints.get(j.joint) else {
                continue;
            };
            let stream = &self.output.stream;
            let mut logged = stream.log(series.commanded.clone(), &Scalars::single(j.commanded));
            if let Some(m) = j.measured {
                logged = logged.and(stream.log(series.measured.clone(), &Scalars::single(m)));
            }
            if j.measured.is_some() && !j.stale {
                logged = logged.and(stream.log(series.error.clone(), &Scalars::single(j.error)));
            }
            self.note(logged);
        }
        let joints: Vec<usize> = sample.joints().iter().map(|j| j.joint).collect();
        self.log_trees(&joints, true, sample.bus == 0);
    }

    /// Logs the series of the state's joints `joints` beside a pose (the
    /// commanded, the measured, their difference), then the trees.
    pub(super) fn log_state(&mut self, joints: &[usize], ghost: bool, world: bool) {
        for &i in joints {
            let (Some(series), Some(&c), Some(&m)) = (
                self.joints.get(i),
                self.commanded.get(i),
                self.measured.get(i),
            ) else {
                continue;
            };
            let stream = &self.output.stream;
            let mut logged = Ok(());
            if let Some(c) = c {
                logged = stream.log(series.commanded.clone(), &Scalars::single(c));
            }
            if let Some(m) = m {
                logged = logged.and(stream.log(series.measured.clone(), &Scalars::single(m)));
            }
            if let (Some(c), Some(m)) = (c, m) {
                logged = logged.and(stream.log(series.error.clone(), &Scalars::single(c - m)));
            }
            self.note(logged);
        }
        self.log_trees(joints, ghost, world);
    }

    /// The joint angles the trees are posed by, rad: the robot's
    /// (measured, else commanded) or the ghost's (commanded, else
    /// measured); wheels at 0.
    pub(super) fn angles(&self, ghost: bool) -> Vec<f64> {
        let (first, second) = if ghost {
            (&self.commanded, &self.measured)
        } else {
            (&self.measured, &self.commanded)
        };
        self.joints
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let v = first[i].or(second[i]).unwrap_or(0.0);
                if s.wheel {
                    0.0
                } else {
                    self.units.to_rad(v)
                }
            })
            .collect()
    }

    /// Poses joints `joints` of the robot's tree (and of the ghost's, with
    /// `ghost`); with `world`, the bodies and the paths too.
    pub(super) fn log_trees(&mut self, joints: &[usize], ghost: bool, world: bool) {
        let trees: &[bool] = if ghost { &[false, true] } else { &[false] };
        for &is_ghost in trees {
            let q = self.angles(is_ghost);
            let Some(space) = &mut self.space else { return };
            let stream = &self.output.stream;
            let mut logged = Ok(());
            if is_ghost && !space.ghost_drawn {
                space.ghost_drawn = true;
                logged = super::scene::ghost(stream, &space.tree, &space.paths);
            }
            for &i in joints {
                let (Some(&angle), Some(path)) = (q.get(i), space.paths.robot.get(i)) else {
                    continue;
                };
                let path = if is_ghost {
                    space.paths.ghost[i].clone()
                } else {
                    path.clone()
                };
                logged = logged.and(stream.log(path, &transform(&space.tree.local(i, angle))));
            }
            self.note(logged);
            if world {
                self.log_world(is_ghost, &q);
            }
        }
    }

    /// A tree's body in the world (a legged one's, from its feet) and,
    /// for the robot's, where the tool or the feet are.
    fn log_world(&mut self, ghost: bool, q: &[f64]) {
        let Some(space) = &mut self.space else { return };
        let local = space.tracked_at(q);
        let body = if space.legged {
            space.bodies[usize::from(ghost)].step(&local)
        } else {
            Isometry3::identity()
        };
        let stream = &self.output.stream;
        let mut logged = Ok(());
        if space.legged {
            let root = if ghost { GHOST } else { ROBOT };
            logged = stream.log(root, &transform(&body));
        }
        if !ghost {
            for ((p, trace), at) in local.iter().zip(&mut space.traces).zip(&space.trace_paths) {
                let w = body * p;
                trace.push(w);
                let point = Points3D::new([[w.x, w.y, w.z].map(mm_to_m)]).with_radii([0.006f32]);
                logged = logged.and(stream.log(at.clone(), &point));
            }
        }
        self.note(logged);
    }

    /// Logs each path whole, when it has one (static: the whole run's).
    pub(super) fn log_traces(&mut self) {
        let Some(space) = &self.space else { return };
        let stream = &self.output.stream;
        let mut logged = Ok(());
        for (trace, at) in space.traces.iter().zip(&space.trace_paths) {
            if trace.is_short() {
                continue;
            }
            let line = LineStrips3D::new([trace.metres()]).with_radii([0.002f32]);
            logged = logged.and(stream.log_static(at.join(&path("trace", [])), &line));
        }
        self.note(logged);
    }

    /// A telemetry message other than a cycle, as an event (a grasp's
    /// readings as series too).
    pub(super) fn telemetry_event(&mut self, message: &Telemetry) {
        let name = |i: usize| {
            self.joints
                .get(i)
                .map_or("?", |s| s.name.as_str())
                .to_owned()
        };
        let (time, level, text) = match message {
            Telemetry::Fault(f) => (Some(f.time_s), Level::Error, format!("fault: {f}")),
            Telemetry::Stall(s) => {
                let what = if s.held {
                    format!("stalled at {:.2}, held pressed", s.position)
                } else {
                    "follows again".to_owned()
                };
                let text = format!("joint `{}` (ID {}) {what}", name(s.joint), s.servo_id);
                (Some(s.time_s), Level::Warning, text)
            }
            Telemetry::Grasp(g) => {
                let text = format!("grasp of `{}`: {:?}", name(g.joint), g.event);
                self.grasp_readings(g);
                (Some(g.time_s), Level::Info, text)
            }
            Telemetry::Rejected(r) => (
                None,
                Level::Warning,
                format!("command not carried out: {r}"),
            ),
            Telemetry::Live { event, time_s } => {
                let text = format!("live following: {event:?}");
                (Some(*time_s), Level::Warning, text)
            }
            Telemetry::Finished(finish) => (None, Level::Info, format!("run ended: {finish:?}")),
            _ => return,
        };
        self.event(time, level, &text);
    }

    /// The temperature and current a grasp's event read, as series.
    fn grasp_readings(&mut self, g: &servobus_runtime::grasp::GraspReport) {
        use servobus_runtime::grasp::GraspEvent;
        let (temperature, current) = match g.event {
            GraspEvent::Lowered {
                temperature_c,
                current_ma,
                ..
            }
            | GraspEvent::LetGo {
                temperature_c,
                current_ma,
                ..
            } => (temperature_c, current_ma),
            _ => return,
        };
        let Some(series) = self.joints.get(g.joint) else {
            return;
        };
        let (t_path, c_path) = (series.temperature.clone(), series.current.clone());
        self.set_time(g.time_s);
        let stream = &self.output.stream;
        let mut logged = stream.log(t_path, &Scalars::single(temperature));
        if let Some(ma) = current {
            logged = logged.and(stream.log(c_path, &Scalars::single(ma)));
        }
        self.note(logged);
    }
}
