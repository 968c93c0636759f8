//! Walking: a six-legged gait that carries the body along segments of
//! body velocity while every stance foot stays where it was put down.
//!
//! ```text
//!  leg phase   0 ........ 1-beta ................. 1
//!              |  swing   |          stance        |
//!              lift, swing to the next foothold; planted while the body
//!              moves over it (beta: the duty factor of the gait)
//! ```
//!
//! The body's velocity (forward, left, turn) blends smoothly from one
//! segment to the next (a quintic step centred on each change, so the
//! distance covered is what the segments ask). A swing foot lands where
//! its neutral place (where it was before the walk, seen from the body)
//! will be at the middle of its next stance, so stance feet sweep evenly
//! about their neutral places. After the last segment every leg steps
//! once more to its neutral place under the stopped body.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector2};
use thiserror::Error;

use crate::geometry::Poses;
use crate::legs::{LegError, Legs, PoseSample};
use crate::support::{support_margin, Margins};

/// A walking gait: which legs swing together.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Gait {
    /// Two tripods alternate: half the legs on the ground (duty 1/2).
    Tripod,
    /// One leg per side at a time, the sides half a cycle apart (duty 2/3).
    Ripple,
    /// One leg at a time, rear to front, right then left (duty 5/6).
    Wave,
}

impl Gait {
    /// The fraction of a step period each leg spends on the ground.
    pub fn duty(self) -> f64 {
        match self {
            Gait::Tripod => 0.5,
            Gait::Ripple => 2.0 / 3.0,
            Gait::Wave => 5.0 / 6.0,
        }
    }

    /// When each leg's swing starts, as a fraction of the period: legs
    /// `[left front, left middle, left rear, right front, right middle,
    /// right rear]`.
    fn offsets(self) -> [f64; 6] {
        match self {
            Gait::Tripod => [0.0, 0.5, 0.0, 0.5, 0.0, 0.5],
            Gait::Ripple => [2.0 / 3.0, 1.0 / 3.0, 0.0, 1.0 / 6.0, 5.0 / 6.0, 0.5],
            Gait::Wave => [5.0 / 6.0, 4.0 / 6.0, 3.0 / 6.0, 2.0 / 6.0, 1.0 / 6.0, 0.0],
        }
    }
}

/// One segment of a walk: a body velocity held for a time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkSegment {
    /// Forward and leftward speed of the body, in its own frame, mm/s.
    pub velocity_mm_s: [f64; 2],
    /// Turning speed, rad/s (positive: to the left).
    pub turn_rad_s: f64,
    /// How long, s.
    pub duration_s: f64,
}

/// A walk: the gait and its step, and the body's velocity segments.
#[derive(Debug, Clone, PartialEq)]
pub struct Walk {
    /// Which legs swing together.
    pub gait: Gait,
    /// The longest a stance foot may sweep under the body, mm (`None`: as
    /// far as the legs reach).
    pub stride_mm: Option<f64>,
    /// How high a swing foot rises above the ground, mm.
    pub lift_mm: f64,
    /// One step cycle (every leg swings once), s.
    pub period_s: f64,
    /// The body's velocity, segment after segment.
    pub segments: Vec<WalkSegment>,
    /// Samples at most this far apart in time, s.
    pub step_s: f64,
}

/// A planned walk: joint samples and what the body and feet do.
#[derive(Debug, Clone, PartialEq)]
pub struct WalkPlan {
    /// Every joint at each sample (radians, robot order), from the walk's
    /// start.
    pub samples: Vec<PoseSample>,
    /// Where the body ends, in the frame it started in (x forward, y left;
    /// mm) and how far it turned (rad).
    pub end: [f64; 3],
    /// The length of the body's path, mm.
    pub distance_mm: f64,
    /// The smallest distance from the body's centre to the edge of the
    /// polygon of the feet on the ground, mm (negative: outside).
    pub min_margin_mm: f64,
    /// The start of every stretch of time the margin spends under
    /// [`LOW_MARGIN_MM`]: the time (s) and the lowest margin (mm).
    pub low_margins: Vec<(f64, f64)>,
}

/// The stability margin under which a walk is worth a warning, mm.
pub const LOW_MARGIN_MM: f64 = 10.0;

/// Why a walk cannot be planned.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum WalkError {
    /// Gaits are for six legs, three a side.
    #[error(
        "a walk needs six legs, three on each side; this robot has {left} left and {right} right"
    )]
    Legs {
        /// Feet on the left (y > 0).
        left: usize,
        /// Feet on the right.
        right: usize,
    },
    /// A segment asks a stance foot to sweep further than the stride.
    #[error("segment {segment} needs a stride of {needed_mm:.1} mm, more than the stride {stride_mm:.1} mm (slow it down or shorten the period)")]
    Stride {
        /// The segment (0-based).
        segment: usize,
        /// The sweep it needs, mm.
        needed_mm: f64,
        /// The stride allowed, mm.
        stride_mm: f64,
    },
    /// A leg cannot reach where the walk puts its foot.
    #[error(transparent)]
    Leg(#[from] LegError),
    /// A step period, a sampling step or a segment duration that is not a
    /// positive number of seconds.
    #[error("the step period, the sampling step and every segment's duration must be positive times in s")]
    Times,
    /// The walk would take more steps or samples than [`MAX_WALK_SAMPLES`]
    /// (a tiny period or step, or a very long walk): refused before any
    /// is made.
    #[error("the walk would take {count:.0} steps or samples, more than the limit of {MAX_WALK_SAMPLES}")]
    TooLong {
        /// The steps of one leg or the samples it would take.
        count: f64,
    },
}

/// The most samples, or swings of one leg, a walk is planned with: a
/// million samples of 18 joints is about 150 MB, and an hour's walk at
/// 20 ms takes 180,000.
pub const MAX_WALK_SAMPLES: usize = 1_000_000;

/// The body's velocity over the walk, blended between segments.
struct Profile {
    /// Start time of each velocity change and the change (vx, vy, w).
    steps: Vec<(f64, [f64; 3])>,
    /// Half the width of a blend, s.
    half: f64,
    /// When the body has stopped, s.
    stop: f64,
}

/// The quintic smooth step: 0 below 0, 1 above 1, zero slope and
/// curvature at both ends.
fn smooth(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * u * (10.0 - 15.0 * u + 6.0 * u * u)
}

impl Profile {
    fn new(segments: &[WalkSegment], period: f64) -> Self {
        let shortest = segments
            .iter()
            .map(|s| s.duration_s)
            .fold(f64::INFINITY, f64::min);
        let half = (0.5 * period).min(0.5 * shortest);
        let mut steps = Vec::with_capacity(segments.len() + 1);
        let mut t = half;
        let mut prev = [0.0; 3];
        for s in segments {
            let v = [s.velocity_mm_s[0], s.velocity_mm_s[1], s.turn_rad_s];
            steps.push((t, [v[0] - prev[0], v[1] - prev[1], v[2] - prev[2]]));
            prev = v;
            t += s.duration_s;
        }
        steps.push((t, [-prev[0], -prev[1], -prev[2]]));
        Profile {
            steps,
            half,
            stop: t + half,
        }
    }

    fn velocity(&self, t: f64) -> [f64; 3] {
        let mut v = [0.0; 3];
        for (at, dv) in &self.steps {
            let w = if self.half > 0.0 {
                smooth((t - at + self.half) / (2.0 * self.half))
            } else if t >= *at {
                1.0
            } else {
                0.0
            };
            for k in 0..3 {
                v[k] += dv[k] * w;
            }
        }
        v
    }
}

/// The body's pose over time, integrated on a fine grid.
struct BodyPath {
    dt: f64,
    /// x, y, yaw at each grid point.
    at: Vec<[f64; 3]>,
    length: f64,
}

impl BodyPath {
    fn new(profile: &Profile, until: f64) -> Self {
        let dt = 0.002;
        let n = (until / dt).ceil() as usize + 1;
        let mut at = Vec::with_capacity(n + 1);
        let mut p = [0.0f64; 3];
        let mut length = 0.0;
        at.push(p);
        for k in 0..n {
            // Midpoint rule: the velocity and heading half a step on.
            let tm = (k as f64 + 0.5) * dt;
            let v = profile.velocity(tm);
            let yaw = p[2] + 0.5 * dt * v[2];
            let (s, c) = yaw.sin_cos();
            let dx = (v[0] * c - v[1] * s) * dt;
            let dy = (v[0] * s + v[1] * c) * dt;
            length += dx.hypot(dy);
            p = [p[0] + dx, p[1] + dy, p[2] + v[2] * dt];
            at.push(p);
        }
        BodyPath { dt, at, length }
    }

    fn pose(&self, t: f64, z: f64) -> Isometry3<f64> {
        let x = (t / self.dt).max(0.0);
        let k = (x.floor() as usize).min(self.at.len() - 1);
        let k1 = (k + 1).min(self.at.len() - 1);
        let f = (x - k as f64).clamp(0.0, 1.0);
        let a = self.at[k];
        let b = self.at[k1];
        let m = |i: usize| a[i] + (b[i] - a[i]) * f;
        Isometry3::from_parts(
            Translation3::new(m(0), m(1), z),
            UnitQuaternion::from_euler_angles(0.0, 0.0, m(2)),
        )
    }
}

/// One swing of one leg: from `from` to `to` (ground frame) over
/// `[t0, t1]`.
#[derive(Clone, Copy)]
struct Swing {
    t0: f64,
    t1: f64,
    from: Point3<f64>,
    to: Point3<f64>,
}

/// Plans `walk` for `legs` from joint angles `start` (radians, robot
/// order): the feet start where `start` puts them, on the ground.
///
/// # Errors
/// [`WalkError`]: not six legs three a side, a segment whose stance sweep
/// is longer than the stride, or a leg that cannot reach (with the time).
pub fn plan_walk(legs: &Legs, walk: &Walk, start: &[f64]) -> Result<WalkPlan, WalkError> {
    let mut poses = Poses::new(legs.model());
    let mut neutral = vec![Point3::origin(); legs.len()];
    legs.feet(start, &mut poses, &mut neutral);
    let order = side_order(&neutral)?;
    let beta = walk.gait.duty();
    check_times(walk)?;
    check_stride(walk, &neutral, beta)?;
    // The body stays at its height: the feet's ground is where they are.
    let profile = Profile::new(&walk.segments, walk.period_s);
    let (windows, end) = swing_windows(walk, &order, legs.len(), profile.stop);
    let body = BodyPath::new(&profile, end + walk.period_s);
    let footholds = Footholds::new(neutral, &windows, &body, beta * walk.period_s);
    let (samples, margin) = sample_walk(legs, walk, start, &footholds, &body, end)?;
    let last = body.pose(end, 0.0);
    Ok(WalkPlan {
        samples,
        end: [
            last.translation.x,
            last.translation.y,
            last.rotation.euler_angles().2,
        ],
        distance_mm: body.length,
        min_margin_mm: margin.min,
        low_margins: margin.low,
    })
}

/// Refuses times that are not positive, and a walk that would take more
/// swings of a leg or samples than [`MAX_WALK_SAMPLES`].
fn check_times(walk: &Walk) -> Result<(), WalkError> {
    let period = walk.period_s;
    let positive = |t: f64| t.is_finite() && t > 0.0;
    if !(positive(period)
        && positive(walk.step_s)
        && walk.segments.iter().all(|s| positive(s.duration_s)))
    {
        return Err(WalkError::Times);
    }
    // The walk ends within two periods of its segments' end; both the
    // swings of a leg and the samples are counted before they are made.
    let span = walk.segments.iter().map(|s| s.duration_s).sum::<f64>() + 2.0 * period;
    let count = (span / period).max(span / walk.step_s);
    if count.is_nan() || count > MAX_WALK_SAMPLES as f64 {
        return Err(WalkError::TooLong { count });
    }
    Ok(())
}

/// Each of the `legs` legs' swing windows `(t0, t1)`, legs in `order` (see
/// [`side_order`]), and when the walk ends: windows of its phase that
/// start at or after 0, until one lands where the body, stopped at
/// `stop`, wants the foot.
fn swing_windows(
    walk: &Walk,
    order: &[usize; 6],
    legs: usize,
    stop: f64,
) -> (Vec<Vec<(f64, f64)>>, f64) {
    let (beta, period) = (walk.gait.duty(), walk.period_s);
    let offsets = walk.gait.offsets();
    let settle = stop - 0.5 * beta * period;
    let mut swings: Vec<Vec<(f64, f64)>> = vec![Vec::new(); legs];
    let mut end = stop;
    for (slot, &leg) in order.iter().enumerate() {
        let mut m = 0usize;
        loop {
            let t0 = (offsets[slot] + m as f64) * period;
            let t1 = t0 + (1.0 - beta) * period;
            swings[leg].push((t0, t1));
            m += 1;
            if t1 >= settle {
                end = end.max(t1);
                break;
            }
        }
    }
    (swings, end)
}

/// Where every foot is put down over the walk: its neutral place (ground
/// frame, before the walk) and its swings.
struct Footholds {
    neutral: Vec<Point3<f64>>,
    swings: Vec<Vec<Swing>>,
}

impl Footholds {
    /// The swings of each leg in its `windows`: each lands where the
    /// foot's `neutral` place will be under the `body` at the middle of
    /// the `stance` (s) after it; a foot already there stays down.
    fn new(
        neutral: Vec<Point3<f64>>,
        windows: &[Vec<(f64, f64)>],
        body: &BodyPath,
        stance: f64,
    ) -> Self {
        let mut planted = neutral.clone();
        let mut swings: Vec<Vec<Swing>> = Vec::with_capacity(windows.len());
        for (leg, windows) in windows.iter().enumerate() {
            let mut list = Vec::with_capacity(windows.len());
            for &(t0, t1) in windows {
                let mid = t1 + 0.5 * stance;
                let to = body.pose(mid, 0.0) * neutral[leg];
                // A foot already where it should land stays down.
                if (to - planted[leg]).norm() > 0.5 {
                    list.push(Swing {
                        t0,
                        t1,
                        from: planted[leg],
                        to,
                    });
                    planted[leg] = to;
                }
            }
            swings.push(list);
        }
        Footholds { neutral, swings }
    }
}

/// Samples the walk every `walk.step_s` or less up to `end`: every joint
/// from `start` on, placing the feet of `footholds` under the `body`, and
/// the stability margins on the way.
fn sample_walk(
    legs: &Legs,
    walk: &Walk,
    start: &[f64],
    footholds: &Footholds,
    body: &BodyPath,
    end: f64,
) -> Result<(Vec<PoseSample>, Margins), WalkError> {
    let steps = (end / walk.step_s).ceil().max(1.0) as usize;
    let mut q = start.to_vec();
    let mut samples = Vec::with_capacity(steps + 1);
    let mut feet = footholds.neutral.clone();
    let mut margin = Margins::default();
    for k in 0..=steps {
        let t = end * k as f64 / steps as f64;
        let mut on_ground = Vec::with_capacity(legs.len());
        for (leg, list) in footholds.swings.iter().enumerate() {
            let (p, down) = foot_at(list, &footholds.neutral[leg], t, walk.lift_mm);
            feet[leg] = p;
            if down {
                on_ground.push(Vector2::new(p.x, p.y));
            }
        }
        let pose = body.pose(t, 0.0);
        margin.add(t, support_margin(&on_ground, &pose));
        legs.place_from(&pose, &feet, t, &mut q)?;
        samples.push(PoseSample { t, q: q.clone() });
    }
    Ok((samples, margin))
}

/// Where a foot with swings `list` is at `t`, and whether it is down.
fn foot_at(list: &[Swing], start: &Point3<f64>, t: f64, lift: f64) -> (Point3<f64>, bool) {
    let mut p = *start;
    for s in list {
        if t >= s.t1 {
            p = s.to;
        } else if t > s.t0 {
            let u = (t - s.t0) / (s.t1 - s.t0);
            let h = smooth(u);
            let mut at = s.from + (s.to - s.from) * h;
            // 64 u^3 (1-u)^3 rises to 1 at the middle, flat at both ends.
            at.z += lift * 64.0 * (u * (1.0 - u)).powi(3);
            return (at, false);
        } else {
            break;
        }
    }
    (p, true)
}

/// The legs as `[left front, middle, rear, right front, middle, rear]`
/// (indices into `feet`), from where the feet are.
fn side_order(feet: &[Point3<f64>]) -> Result<[usize; 6], WalkError> {
    let mut left: Vec<usize> = (0..feet.len()).filter(|&i| feet[i].y > 0.0).collect();
    let mut right: Vec<usize> = (0..feet.len()).filter(|&i| feet[i].y <= 0.0).collect();
    if left.len() != 3 || right.len() != 3 {
        return Err(WalkError::Legs {
            left: left.len(),
            right: right.len(),
        });
    }
    left.sort_by(|&a, &b| feet[b].x.total_cmp(&feet[a].x));
    right.sort_by(|&a, &b| feet[b].x.total_cmp(&feet[a].x));
    Ok([left[0], left[1], left[2], right[0], right[1], right[2]])
}

/// Refuses a segment whose stance sweep exceeds the walk's stride.
fn check_stride(walk: &Walk, neutral: &[Point3<f64>], beta: f64) -> Result<(), WalkError> {
    let Some(stride) = walk.stride_mm else {
        return Ok(());
    };
    for (i, s) in walk.segments.iter().enumerate() {
        let needed = neutral
            .iter()
            .map(|p| {
                let vx = s.velocity_mm_s[0] - s.turn_rad_s * p.y;
                let vy = s.velocity_mm_s[1] + s.turn_rad_s * p.x;
                vx.hypot(vy) * beta * walk.period_s
            })
            .fold(0.0, f64::max);
        if needed > stride + 1e-9 {
            return Err(WalkError::Stride {
                segment: i,
                needed_mm: needed,
                stride_mm: stride,
            });
        }
    }
    Ok(())
}
