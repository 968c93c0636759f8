//! What a planned motion does in space, for `servobus plan`: the tool's
//! peak speed and how close the arm comes to a singular pose, the closest
//! any joint comes to a limit, and for a legged robot how high the feet
//! rise and the worst stability margin.

use servobus_kinematics::{
    move_on_feet, support_margin, ArmIk, Geometry, Isometry3, Legs, Point3, Poses, Vector2,
    LOW_MARGIN_MM,
};
use servobus_trajectory::{JointState, Trajectory};

use crate::motion::Motion;
use crate::robot::Robot;
use crate::tool::TOOL_FRAME;

/// How far from the ground (the feet's height at the start) a foot may be
/// and still count as on it, mm.
const ON_GROUND_MM: f64 = 0.05;

/// How high above the ground a foot must be to count as stepping, mm.
const STEP_MM: f64 = 1.0;

/// The spatial figures of a planned motion (see [`spatial_summary`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SpatialSummary {
    /// The arm's tool, when the robot has a `tool` frame.
    pub tool: Option<ToolSummary>,
    /// The feet, when the robot has `foot_<leg>` frames.
    pub feet: Option<FeetSummary>,
    /// The joint that comes closest to one of its limits, and how close
    /// (the motion's units).
    pub closest_limit: Option<(String, f64)>,
}

/// The tool's path.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolSummary {
    /// Its fastest speed, mm/s.
    pub peak_speed_mm_s: f64,
    /// The length of its path, mm.
    pub path_mm: f64,
    /// The closest the arm comes to a singular pose: the smallest
    /// dexterity (mm/rad; see `ArmIk::dexterity`).
    pub min_dexterity: f64,
    /// Where it is at each sample (mm, base frame), for plots.
    pub path: Vec<[f64; 3]>,
}

/// The feet's paths.
#[derive(Debug, Clone, PartialEq)]
pub struct FeetSummary {
    /// The highest a foot rises above the ground while others stand on it
    /// (a step), mm.
    pub max_lift_mm: f64,
    /// The smallest stability margin while some feet step and at least
    /// three stand (the body's centre to the edge of the polygon of the
    /// feet on the ground), mm; `None` when no foot steps.
    pub min_margin_mm: Option<f64>,
    /// When feet step (a walk): how far the body travels over the ground
    /// (mm), from the feet at standing height, which move under the body
    /// by the inverse of its move; `None` when no foot steps.
    pub distance_mm: Option<f64>,
    /// How far the body turns (rad), as `distance_mm`.
    pub turn_rad: Option<f64>,
    /// The samples (s) at which the margin first drops under 10 mm.
    pub low_margins_s: Vec<f64>,
    /// Each foot's position at each sample (mm, body frame), for plots.
    pub paths: Vec<(String, Vec<[f64; 3]>)>,
}

/// Samples `trajectory` (planned from `motion`) every `step_s` and says
/// what it does in space; `None` when the robot has no geometry.
pub fn spatial_summary(
    motion: &Motion,
    robot: &Robot,
    trajectory: &Trajectory,
    step_s: f64,
) -> Option<SpatialSummary> {
    let model = robot.geometry()?;
    let mut tool = ArmIk::new(&model, TOOL_FRAME).ok().map(ToolTrack::new);
    let mut feet = Legs::new(&model)
        .ok()
        .map(|legs| FeetTrack::new(legs, &model));
    let n = trajectory.joints();
    let mut state = vec![JointState::default(); n];
    let mut q = vec![0.0; n];
    let steps = (trajectory.duration() / step_s).ceil() as usize;
    let mut closest: Option<(usize, f64)> = None;
    for k in 0..=steps {
        let t = (k as f64 * step_s).min(trajectory.duration());
        trajectory.sample(t, &mut state);
        for (v, s) in q.iter_mut().zip(&state) {
            *v = s.position;
        }
        closest_to_limit(&model, &q, &mut closest);
        if let Some(tool) = &mut tool {
            tool.sample(&q);
        }
        if let Some(feet) = &mut feet {
            feet.sample(k == 0, t, &q);
        }
    }
    let closest_limit = closest.map(|(j, gap)| {
        (
            motion.joints.get(j).cloned().unwrap_or_default(),
            motion.units.from_rad(gap),
        )
    });
    Some(SpatialSummary {
        tool: tool.map(|tool| tool.finish(step_s)),
        feet: feet.map(FeetTrack::finish),
        closest_limit,
    })
}

/// Updates `closest` (a joint and its gap, rad) with the joint of `q`
/// closest to one of its limits, when it is closer.
fn closest_to_limit(model: &Geometry, q: &[f64], closest: &mut Option<(usize, f64)>) {
    for (j, &v) in q.iter().enumerate() {
        if let Some((lo, hi)) = model.limits(j) {
            let gap = (v - lo).min(hi - v);
            if closest.is_none_or(|(_, g)| gap < g) {
                *closest = Some((j, gap));
            }
        }
    }
}

/// The tool's path and the arm's smallest dexterity over the samples.
struct ToolTrack {
    arm: ArmIk,
    path: Vec<[f64; 3]>,
    dexterity: f64,
}

impl ToolTrack {
    /// A track of `arm`'s tool, with no sample yet.
    fn new(arm: ArmIk) -> Self {
        ToolTrack {
            arm,
            path: Vec::new(),
            dexterity: f64::INFINITY,
        }
    }

    /// Adds the tool's position and the arm's dexterity at joint positions `q`.
    fn sample(&mut self, q: &[f64]) {
        let chain: Vec<f64> = self.arm.joints().iter().map(|&j| q[j]).collect();
        let p = self.arm.frame_pose(&chain).translation.vector;
        self.path.push([p.x, p.y, p.z]);
        self.dexterity = self.dexterity.min(self.arm.dexterity(&chain));
    }

    /// The tool's figures from samples `step_s` apart.
    fn finish(self, step_s: f64) -> ToolSummary {
        let path_mm = self
            .path
            .windows(2)
            .map(|w| dist(&w[0], &w[1]))
            .sum::<f64>();
        let peak = self
            .path
            .windows(2)
            .map(|w| dist(&w[0], &w[1]) / step_s)
            .fold(0.0, f64::max);
        ToolSummary {
            peak_speed_mm_s: peak,
            path_mm,
            min_dexterity: self.dexterity,
            path: self.path,
        }
    }
}

/// The feet's paths over the samples, and what the steps and the body's
/// travel add up to so far.
struct FeetTrack {
    legs: Legs,
    poses: Poses,
    /// Each foot at the current sample (body frame, mm).
    feet: Vec<Point3<f64>>,
    paths: Vec<Vec<[f64; 3]>>,
    /// The feet's height at the start, mm.
    ground: f64,
    lift: f64,
    margin: Option<f64>,
    /// When the margin first dropped under [`LOW_MARGIN_MM`] in each dip, s.
    low: Vec<f64>,
    in_dip: bool,
    /// Where each foot on the ground was at the last sample (`None`: in the air).
    before: Vec<Option<Vector2<f64>>>,
    distance: f64,
    turn: f64,
}

impl FeetTrack {
    /// A track of `legs`'s feet in `model`, with no sample yet.
    fn new(legs: Legs, model: &Geometry) -> Self {
        let n = legs.len();
        FeetTrack {
            legs,
            poses: Poses::new(model),
            feet: vec![Point3::origin(); n],
            paths: vec![Vec::new(); n],
            ground: f64::INFINITY,
            lift: 0.0,
            margin: None,
            low: Vec::new(),
            in_dip: false,
            before: vec![None; n],
            distance: 0.0,
            turn: 0.0,
        }
    }

    /// Adds the feet at joint positions `q`, time `t`; the `first` sample
    /// sets the ground.
    fn sample(&mut self, first: bool, t: f64, q: &[f64]) {
        self.legs.feet(q, &mut self.poses, &mut self.feet);
        for (path, p) in self.paths.iter_mut().zip(&self.feet) {
            path.push([p.x, p.y, p.z]);
        }
        // The ground is where the feet stand at the start; the walk's
        // figures count where at least three feet are on it (a body
        // move lifts or tilts the body over all six instead).
        if first {
            self.ground = self.feet.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
        }
        self.track_body();
        self.track_steps(t);
    }

    /// Adds the body's move since the last sample, from the feet down at both.
    fn track_body(&mut self) {
        let ground = self.ground;
        let now: Vec<Option<Vector2<f64>>> = self
            .feet
            .iter()
            .map(|p| ((p.z - ground).abs() < ON_GROUND_MM).then(|| Vector2::new(p.x, p.y)))
            .collect();
        if let Some((angle, shift)) = move_on_feet(&now, &self.before) {
            self.distance += shift.norm();
            self.turn += angle;
        }
        self.before = now;
    }

    /// While some feet step and at least three stand, adds the lift and the
    /// stability margin at time `t`.
    fn track_steps(&mut self, t: f64) {
        let ground = self.ground;
        let down: Vec<Vector2<f64>> = self
            .feet
            .iter()
            .filter(|p| (p.z - ground).abs() < ON_GROUND_MM)
            .map(|p| Vector2::new(p.x, p.y))
            .collect();
        let stepping = self.feet.iter().any(|p| p.z > ground + STEP_MM);
        if down.len() >= 3 && stepping {
            for p in &self.feet {
                self.lift = self.lift.max(p.z - ground);
            }
            let m = support_margin(&down, &Isometry3::identity());
            self.margin = Some(self.margin.map_or(m, |x: f64| x.min(m)));
            if m < LOW_MARGIN_MM && !self.in_dip {
                self.low.push(t);
            }
            self.in_dip = m < LOW_MARGIN_MM;
        } else {
            self.in_dip = false;
        }
    }

    /// The feet's figures.
    fn finish(self) -> FeetSummary {
        let walked = self.lift > STEP_MM;
        let legs = &self.legs;
        FeetSummary {
            distance_mm: walked.then_some(self.distance),
            turn_rad: walked.then_some(self.turn),
            max_lift_mm: self.lift,
            min_margin_mm: self.margin,
            low_margins_s: self.low,
            paths: (0..legs.len())
                .map(|i| legs.name(i).unwrap_or("?").to_owned())
                .zip(self.paths)
                .collect(),
        }
    }
}

/// The distance between two points, mm.
fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}
