//! What a planned motion does in space, for `servobus plan`: the tool's
//! peak speed and how close the arm comes to a singular pose, the closest
//! any joint comes to a limit, and for a legged robot how high the feet
//! rise and the worst stability margin.

use servobus_kinematics::{
    planar_motion, support_margin, ArmIk, Isometry3, Legs, Point3, Poses, Vector2, LOW_MARGIN_MM,
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
    let arm = ArmIk::new(&model, TOOL_FRAME).ok();
    let legs = Legs::new(&model).ok();
    let n = trajectory.joints();
    let mut state = vec![JointState::default(); n];
    let mut q = vec![0.0; n];
    let steps = (trajectory.duration() / step_s).ceil() as usize;
    let mut tool_path = Vec::new();
    let mut dexterity = f64::INFINITY;
    let mut closest: Option<(usize, f64)> = None;
    let mut poses = Poses::new(&model);
    let mut feet = vec![Point3::origin(); legs.as_ref().map_or(0, Legs::len)];
    let mut feet_paths: Vec<Vec<[f64; 3]>> = vec![Vec::new(); feet.len()];
    let (mut ground, mut lift) = (f64::INFINITY, 0.0f64);
    let mut margin: Option<f64> = None;
    let mut low = Vec::new();
    let mut in_dip = false;
    let mut before: Vec<Option<Vector2<f64>>> = vec![None; feet.len()];
    let (mut distance, mut turn) = (0.0f64, 0.0f64);
    for k in 0..=steps {
        let t = (k as f64 * step_s).min(trajectory.duration());
        trajectory.sample(t, &mut state);
        for (v, s) in q.iter_mut().zip(&state) {
            *v = s.position;
        }
        for (j, &v) in q.iter().enumerate() {
            if let Some((lo, hi)) = model.limits(j) {
                let gap = (v - lo).min(hi - v);
                if closest.is_none_or(|(_, g)| gap < g) {
                    closest = Some((j, gap));
                }
            }
        }
        if let Some(arm) = &arm {
            let chain: Vec<f64> = arm.joints().iter().map(|&j| q[j]).collect();
            let p = arm.frame_pose(&chain).translation.vector;
            tool_path.push([p.x, p.y, p.z]);
            dexterity = dexterity.min(arm.dexterity(&chain));
        }
        if let Some(legs) = &legs {
            legs.feet(&q, &mut poses, &mut feet);
            for (path, p) in feet_paths.iter_mut().zip(&feet) {
                path.push([p.x, p.y, p.z]);
            }
            // The ground is where the feet stand at the start; the walk's
            // figures count where at least three feet are on it (a body
            // move lifts or tilts the body over all six instead).
            if k == 0 {
                ground = feet.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
            }
            let down: Vec<Vector2<f64>> = feet
                .iter()
                .filter(|p| (p.z - ground).abs() < ON_GROUND_MM)
                .map(|p| Vector2::new(p.x, p.y))
                .collect();
            // The body's move since the last sample, from the feet down
            // at both.
            let now: Vec<Option<Vector2<f64>>> = feet
                .iter()
                .map(|p| ((p.z - ground).abs() < ON_GROUND_MM).then(|| Vector2::new(p.x, p.y)))
                .collect();
            let (a, b): (Vec<_>, Vec<_>) = now
                .iter()
                .zip(&before)
                .filter_map(|(n, b)| n.zip(*b))
                .unzip();
            if a.len() >= 3 {
                let (angle, shift) = planar_motion(&a, &b);
                distance += shift.norm();
                turn += angle;
            }
            before = now;
            let stepping = feet.iter().any(|p| p.z > ground + STEP_MM);
            if down.len() >= 3 && stepping {
                for p in &feet {
                    lift = lift.max(p.z - ground);
                }
                let m = support_margin(&down, &Isometry3::identity());
                margin = Some(margin.map_or(m, |x: f64| x.min(m)));
                if m < LOW_MARGIN_MM && !in_dip {
                    low.push(t);
                }
                in_dip = m < LOW_MARGIN_MM;
            } else {
                in_dip = false;
            }
        }
    }
    let tool = arm.map(|_| {
        let path_mm = tool_path
            .windows(2)
            .map(|w| dist(&w[0], &w[1]))
            .sum::<f64>();
        let peak = tool_path
            .windows(2)
            .map(|w| dist(&w[0], &w[1]) / step_s)
            .fold(0.0, f64::max);
        ToolSummary {
            peak_speed_mm_s: peak,
            path_mm,
            min_dexterity: dexterity,
            path: tool_path,
        }
    });
    let walked = lift > STEP_MM;
    let feet = legs.map(|legs| FeetSummary {
        distance_mm: walked.then_some(distance),
        turn_rad: walked.then_some(turn),
        max_lift_mm: lift,
        min_margin_mm: margin,
        low_margins_s: low,
        paths: (0..legs.len())
            .map(|i| legs.name(i).unwrap_or("?").to_owned())
            .zip(feet_paths)
            .collect(),
    });
    let closest_limit = closest.map(|(j, gap)| {
        (
            motion.joints.get(j).cloned().unwrap_or_default(),
            motion.units.from_rad(gap),
        )
    });
    Some(SpatialSummary {
        tool,
        feet,
        closest_limit,
    })
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}
