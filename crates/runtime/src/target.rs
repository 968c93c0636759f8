//! Live targets: joint positions sent to a running loop while it runs (a
//! policy, a leader arm, another program), which the loop follows with a
//! jerk-limited step every cycle (see [`crate::live`]).
//!
//! A [`Chunk`] is a policy's timed sequence of positions (an action
//! chunk): the loop follows it as a timed path through its points, and a
//! new chunk replaces what is left of the last one.
//!
//! A [`TargetSender`] checks each [`LiveTarget`] and [`Chunk`] before it reaches the loop:
//! a value that is not finite, an unknown joint or the wrong number of
//! joints is refused ([`TargetError`], counted); a position outside its
//! joint's limits is clamped (counted). Targets travel on a bounded
//! channel; the loop takes every target waiting at the start of a cycle.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crossbeam_channel::Sender;
use serde::Serialize;
use servobus_trajectory::JointLimits;

use crate::config::Units;
use crate::live::EnvelopeReport;
use crate::report::Quantiles;
use crate::stats::Histogram;

/// The joints of a target (`T`: a position) or of a chunk (`T`: one
/// position per point).
#[derive(Debug, Clone, PartialEq)]
enum Joints<T = f64> {
    /// Every joint, in the robot's joint order.
    All(Vec<T>),
    /// Some joints, by name; the others keep their targets.
    Named(Vec<(String, T)>),
}

/// Joint positions for a running loop to go to, in radians, stamped with
/// the time they were taken (seconds on any clock the sender keeps: only
/// differences between stamps and their arrival matter).
#[derive(Debug, Clone, PartialEq)]
pub struct LiveTarget {
    stamp: f64,
    joints: Joints,
    velocities: Option<Vec<f64>>,
    taken: Option<Instant>,
    /// Joints told to grasp, by name, with their effort (percent).
    grasps: Vec<(String, f64)>,
}

impl LiveTarget {
    /// Every joint's position, in the robot's joint order (rad).
    pub fn all(stamp: f64, positions: Vec<f64>) -> Self {
        LiveTarget {
            stamp,
            joints: Joints::All(positions),
            velocities: None,
            taken: None,
            grasps: Vec::new(),
        }
    }

    /// Some joints' positions by name (rad); the others keep their targets.
    pub fn named(stamp: f64, joints: Vec<(String, f64)>) -> Self {
        LiveTarget {
            stamp,
            joints: Joints::Named(joints),
            velocities: None,
            taken: None,
            grasps: Vec::new(),
        }
    }

    /// The target's velocities (rad/s), one per joint given, in the same
    /// order; without them the loop estimates them from the stamps.
    pub fn with_velocities(mut self, velocities: Vec<f64>) -> Self {
        self.velocities = Some(velocities);
        self
    }

    /// Tells the joints named to grasp (a gripper closing on an object):
    /// each closes towards its `min` at a bounded speed until it meets
    /// something, then holds there, pushing with `effort` percent of its
    /// servo's torque (its torque limit set to it), while its temperature
    /// is watched (see [`crate::grasp`]). A later position target for the
    /// joint releases it. A joint may not have a position in the same
    /// target; the others named in it follow as usual.
    pub fn with_grasps(mut self, grasps: Vec<(String, f64)>) -> Self {
        self.grasps = grasps;
        self
    }

    /// The moment (on this process's monotonic clock) the positions were
    /// taken: the run then measures the latency from it to the goals on the
    /// wire ([`LiveReport::latency_ms`]; meaningful on the real clock).
    pub fn taken_at(mut self, taken: Instant) -> Self {
        self.taken = Some(taken);
        self
    }
}

/// The most points a [`Chunk`] may hold (a policy's chunks hold 16 to
/// 100): the loop keeps room for this many per joint from the start, so
/// that following a chunk allocates nothing.
pub const MAX_CHUNK_POINTS: usize = 1000;

/// When a chunk's points are due.
#[derive(Debug, Clone, PartialEq)]
enum Times {
    /// Every `dt` s, the first at `t0` (the arrival when absent).
    Every { t0: Option<f64>, dt: f64 },
    /// At these stamps (increasing).
    At(Vec<f64>),
}

/// A timed sequence of joint positions (an action chunk of a policy such
/// as ACT, diffusion or pi0), in radians: the loop follows it as a timed
/// path through its points, within the joints' limits. A new chunk
/// replaces what is left of the current one from the commanded state, and
/// its points already past are skipped. Stamps are on the sender's clock,
/// as a [`LiveTarget`]'s.
#[derive(Debug, Clone, PartialEq)]
pub struct Chunk {
    times: Times,
    joints: Joints<Vec<f64>>,
    taken: Option<Instant>,
}

impl Chunk {
    /// Points `dt` s apart, the first at stamp `t0` (on arrival when
    /// `None`), for the joints named (the others keep their targets).
    pub fn named(t0: Option<f64>, dt: f64, joints: Vec<(String, Vec<f64>)>) -> Self {
        Chunk {
            times: Times::Every { t0, dt },
            joints: Joints::Named(joints),
            taken: None,
        }
    }

    /// Points at the given stamps (increasing), for the joints named.
    pub fn timed(times: Vec<f64>, joints: Vec<(String, Vec<f64>)>) -> Self {
        Chunk {
            times: Times::At(times),
            joints: Joints::Named(joints),
            taken: None,
        }
    }

    /// Points `dt` s apart from `t0` for every joint, in the robot's joint
    /// order (`positions[joint][point]`).
    pub fn all(t0: Option<f64>, dt: f64, positions: Vec<Vec<f64>>) -> Self {
        Chunk {
            times: Times::Every { t0, dt },
            joints: Joints::All(positions),
            taken: None,
        }
    }

    /// The moment the chunk's observation was taken (see
    /// [`LiveTarget::taken_at`]).
    pub fn taken_at(mut self, taken: Instant) -> Self {
        self.taken = Some(taken);
        self
    }
}

/// A chunk as checked: its points' stamps (sender's clock; relative to
/// the arrival when `relative`), and per joint of the robot its positions
/// (rad, within the limits) when given.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ChunkPoints {
    pub times: Vec<f64>,
    pub relative: bool,
    pub joints: Vec<Option<Vec<f64>>>,
}

/// Why a target was refused. The loop keeps its previous target.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TargetError {
    /// A position, velocity or the stamp is NaN or infinite.
    #[error("joint `{joint}`: the target is not a finite number")]
    NotFinite {
        /// The joint (`stamp` for the stamp).
        joint: String,
    },
    /// No joint of the robot has this name.
    #[error("no joint is named `{0}`")]
    UnknownJoint(String),
    /// The target does not give one value per joint.
    #[error("the target has {actual} values, the robot {expected} joints")]
    WrongLength {
        /// The robot's joints.
        expected: usize,
        /// The values given.
        actual: usize,
    },
    /// A chunk's times are not usable: `dt` not a positive finite number,
    /// stamps not finite or not increasing.
    #[error("the chunk's times: {0}")]
    ChunkTimes(String),
    /// A chunk's joints do not all have one position per point.
    #[error("joint `{joint}`: {actual} positions for the chunk's {expected} points")]
    ChunkLength {
        /// The joint.
        joint: String,
        /// The chunk's points.
        expected: usize,
        /// The positions given for the joint.
        actual: usize,
    },
    /// A grasp the joint cannot make: an effort not in (0, 100] percent, a
    /// wheel, or a position for the same joint in the same target.
    #[error("joint `{joint}`: cannot grasp: {why}")]
    Grasp {
        /// The joint.
        joint: String,
        /// Why.
        why: &'static str,
    },
    /// A chunk with no point, or more than [`MAX_CHUNK_POINTS`].
    #[error("a chunk of {0} points: a chunk holds 1 to {MAX_CHUNK_POINTS}")]
    ChunkSize(usize),
    /// The run has ended.
    #[error("the run has ended")]
    Ended,
}

/// A target as checked: per joint of the robot, its position and velocity
/// when given (rad, rad/s).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Checked {
    pub stamp: f64,
    pub joints: Vec<Option<(f64, Option<f64>)>>,
    /// Per joint, the effort (0..=1 of the servo's torque) of a grasp it
    /// was told to make; empty when none was.
    pub grasps: Vec<Option<f64>>,
    pub taken: Option<Instant>,
    /// A chunk's points (`joints` all `None` then).
    pub chunk: Option<ChunkPoints>,
}

/// The longest target latency the report's histogram holds.
const LATENCY_SPAN: Duration = Duration::from_millis(500);

/// The counts of a run's targets.
#[derive(Debug)]
pub(crate) struct TargetCounts {
    received: AtomicU64,
    clamped: AtomicU64,
    refused: AtomicU64,
    timeouts: AtomicU64,
    resumes: AtomicU64,
    followed: AtomicU64,
    /// Set once anything can send targets (a live session): its report
    /// then has its live section, even when nothing came.
    live: AtomicBool,
    /// From a target's taking to the goals on the wire. Made with the
    /// counters, before the run starts: the loop only records into it.
    latency: Mutex<Histogram>,
    /// Per joint, how its commanded path kept to its targets' envelope
    /// (rad); room for every joint made before the run starts.
    envelope: Mutex<Vec<EnvelopeReport>>,
    /// The joints' names and the report's units.
    names: Vec<String>,
    units: Units,
}

impl TargetCounts {
    /// The counters of a run of the joints `names`, reported in `units`.
    pub fn new(names: Vec<String>, units: Units) -> Self {
        TargetCounts {
            envelope: Mutex::new(vec![EnvelopeReport::default(); names.len()]),
            names,
            units,
            ..TargetCounts::default()
        }
    }

    /// Marks the run as a live session: its report has a live section even
    /// when no target came.
    pub fn live_session(&self) {
        self.live.store(true, Ordering::Relaxed);
    }

    /// Takes in the envelope figures of every joint, from the control
    /// loop: it never waits for the lock, and allocates nothing.
    pub fn envelopes(&self, figures: impl Iterator<Item = EnvelopeReport>) {
        if let Ok(mut e) = self.envelope.try_lock() {
            for (slot, f) in e.iter_mut().zip(figures) {
                *slot = f;
            }
        }
    }
}

impl Default for TargetCounts {
    fn default() -> Self {
        TargetCounts {
            envelope: Mutex::new(Vec::new()),
            names: Vec::new(),
            units: Units::Rad,
            received: AtomicU64::default(),
            clamped: AtomicU64::default(),
            refused: AtomicU64::default(),
            timeouts: AtomicU64::default(),
            resumes: AtomicU64::default(),
            followed: AtomicU64::default(),
            live: AtomicBool::new(false),
            latency: Mutex::new(Histogram::new(LATENCY_SPAN)),
        }
    }
}

/// One of the counters.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Count {
    Timeout,
    Resume,
    Followed,
}

impl TargetCounts {
    pub fn add(&self, c: Count) {
        let n = match c {
            Count::Timeout => &self.timeouts,
            Count::Resume => &self.resumes,
            Count::Followed => &self.followed,
        };
        n.fetch_add(1, Ordering::Relaxed);
    }

    /// Records the latency of a target, from the control loop: it never
    /// waits for the lock (a report being read then costs one sample).
    pub fn latency(&self, d: Duration) {
        if let Ok(mut h) = self.latency.try_lock() {
            h.record(d);
        }
    }

    /// The report's figures, if the run had any target.
    pub fn report(&self) -> Option<LiveReport> {
        let get = |a: &AtomicU64| a.load(Ordering::Relaxed);
        let r = LiveReport {
            received: get(&self.received),
            clamped: get(&self.clamped),
            refused: get(&self.refused),
            timeouts: get(&self.timeouts),
            resumes: get(&self.resumes),
            latency_ms: Some(&*self.latency.lock().unwrap_or_else(|e| e.into_inner()))
                .filter(|h| h.count() > 0)
                .map(|h| Quantiles::of(h, Duration::from_millis(1))),
            envelope: {
                let e = self.envelope.lock().unwrap_or_else(|e| e.into_inner());
                let u = self.units;
                self.names
                    .iter()
                    .zip(e.iter())
                    .map(|(name, f)| LiveJoint {
                        name: name.clone(),
                        overshoot: u.from_rad(f.overshoot),
                        allowance: u.from_rad(f.allowance),
                        beyond_allowance: u.from_rad(f.beyond_allowance),
                    })
                    .collect()
            },
        };
        let live = self.live.load(Ordering::Relaxed);
        (live || r.received > 0 || get(&self.followed) > 0).then_some(r)
    }
}

/// How one joint's commanded path kept to the envelope of its targets
/// (the least and greatest of those received in the last 0.5 s), in the
/// report's units.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct LiveJoint {
    /// The joint.
    pub name: String,
    /// The largest distance the commanded path went beyond the envelope.
    pub overshoot: f64,
    /// The stopping distance the joint's limits made unavoidable in that
    /// excursion: its quickest stop from the commanded state where the
    /// excursion began.
    pub allowance: f64,
    /// The largest overshoot beyond its excursion's allowance (0 when the
    /// follower never went further than its limits made it).
    pub beyond_allowance: f64,
}

/// What happened to a run's live targets (in the [`Report`](crate::Report)
/// of a run that followed targets).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct LiveReport {
    /// Targets sent (accepted or refused).
    pub received: u64,
    /// Targets with a position outside its joint's limits (clamped).
    pub clamped: u64,
    /// Targets refused ([`TargetError`]).
    pub refused: u64,
    /// Times no target came for the timeout and the joints stopped.
    pub timeouts: u64,
    /// Times targets came back after a timeout.
    pub resumes: u64,
    /// From the taking of a target ([`LiveTarget::taken_at`]) to the first
    /// goals sent after it, ms, when targets said when they were taken.
    pub latency_ms: Option<Quantiles>,
    /// Per joint, in the robot's joint order: how far the commanded path
    /// went beyond the targets it was given, and what its limits allowed.
    pub envelope: Vec<LiveJoint>,
}

/// A sender of live targets to a run (cheap to clone).
#[derive(Debug, Clone)]
pub struct TargetSender {
    tx: Sender<Arc<Checked>>,
    names: Arc<Vec<String>>,
    limits: Arc<Vec<JointLimits>>,
    counters: Arc<TargetCounts>,
}

impl TargetSender {
    pub(crate) fn new(
        tx: Sender<Arc<Checked>>,
        names: Vec<String>,
        limits: Vec<JointLimits>,
        counters: Arc<TargetCounts>,
    ) -> Self {
        TargetSender {
            tx,
            names: Arc::new(names),
            limits: Arc::new(limits),
            counters,
        }
    }

    /// The robot's joint names, in its joint order.
    pub fn joint_names(&self) -> &[String] {
        &self.names
    }

    /// What the run's targets came to so far (the figures of the report's
    /// [`live`](crate::Report::live)).
    pub fn so_far(&self) -> Option<LiveReport> {
        self.counters.report()
    }

    /// Checks `target` and sends it, waiting while the channel is full.
    /// Returns how many of its positions were clamped to their limits.
    ///
    /// # Errors
    ///
    /// [`TargetError`] when the target is refused (counted; the loop keeps
    /// its previous target) or the run has ended.
    pub fn send(&self, target: LiveTarget) -> Result<usize, TargetError> {
        self.deliver(self.check(target))
    }

    /// Checks `chunk` and sends it, as [`TargetSender::send`] does a
    /// target. Returns how many positions were clamped to their limits.
    ///
    /// # Errors
    ///
    /// [`TargetError`] when the chunk is refused (counted) or the run has
    /// ended.
    pub fn send_chunk(&self, chunk: Chunk) -> Result<usize, TargetError> {
        self.deliver(self.check_chunk(chunk))
    }

    /// Counts a checked target or chunk and sends it on; returns how many
    /// positions were clamped.
    fn deliver(
        &self,
        checked: Result<(Checked, usize), TargetError>,
    ) -> Result<usize, TargetError> {
        self.counters.received.fetch_add(1, Ordering::Relaxed);
        let checked = checked.inspect_err(|_| {
            self.counters.refused.fetch_add(1, Ordering::Relaxed);
        });
        let (checked, clamped) = checked?;
        if clamped > 0 {
            self.counters.clamped.fetch_add(1, Ordering::Relaxed);
        }
        // Wrapped here, on the sender's thread: the control loop only
        // passes the pointer on.
        self.tx
            .send(Arc::new(checked))
            .map_err(|_| TargetError::Ended)?;
        Ok(clamped)
    }

    /// Each joint given with its index in the robot's joint order.
    fn indexed<T>(&self, joints: Joints<T>) -> Result<Vec<(usize, T)>, TargetError> {
        let n = self.names.len();
        match joints {
            Joints::All(p) if p.len() != n => Err(TargetError::WrongLength {
                expected: n,
                actual: p.len(),
            }),
            Joints::All(p) => Ok(p.into_iter().enumerate().collect()),
            Joints::Named(named) => named
                .into_iter()
                .map(
                    |(name, q)| match self.names.iter().position(|x| *x == name) {
                        Some(i) => Ok((i, q)),
                        None => Err(TargetError::UnknownJoint(name)),
                    },
                )
                .collect(),
        }
    }

    fn check_chunk(&self, chunk: Chunk) -> Result<(Checked, usize), TargetError> {
        let n = self.names.len();
        let given = self.indexed(chunk.joints)?;
        let points = given.first().map_or(0, |(_, q)| q.len());
        if points == 0 || points > MAX_CHUNK_POINTS {
            return Err(TargetError::ChunkSize(points));
        }
        let (times, relative, stamp) = match chunk.times {
            Times::Every { t0, dt } => {
                if !(dt.is_finite() && dt > 0.0) {
                    return Err(TargetError::ChunkTimes(format!(
                        "dt {dt} is not a positive number of seconds"
                    )));
                }
                if t0.is_some_and(|t| !t.is_finite()) {
                    return Err(TargetError::NotFinite { joint: "t0".into() });
                }
                let base = t0.unwrap_or(0.0);
                let times: Vec<f64> = (0..points).map(|k| base + k as f64 * dt).collect();
                (times, t0.is_none(), base)
            }
            Times::At(times) => {
                if times.len() != points {
                    return Err(TargetError::ChunkTimes(format!(
                        "{} times for {points} points",
                        times.len()
                    )));
                }
                if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] <= w[0]) {
                    return Err(TargetError::ChunkTimes(
                        "the stamps must be finite and increasing".into(),
                    ));
                }
                let first = times[0];
                (times, false, first)
            }
        };
        let mut joints = vec![None; n];
        let mut clamped = 0;
        for (i, q) in given {
            if q.len() != points {
                return Err(TargetError::ChunkLength {
                    joint: self.names[i].clone(),
                    expected: points,
                    actual: q.len(),
                });
            }
            if q.iter().any(|q| !q.is_finite()) {
                return Err(TargetError::NotFinite {
                    joint: self.names[i].clone(),
                });
            }
            let l = &self.limits[i];
            let q: Vec<f64> = q
                .into_iter()
                .map(|q| {
                    let c = q.clamp(l.min_position, l.max_position);
                    if c != q {
                        clamped += 1;
                    }
                    c
                })
                .collect();
            joints[i] = Some(q);
        }
        Ok((
            Checked {
                stamp,
                joints: vec![None; n],
                grasps: Vec::new(),
                taken: chunk.taken,
                chunk: Some(ChunkPoints {
                    times,
                    relative,
                    joints,
                }),
            },
            clamped,
        ))
    }

    /// The grasps of a target whose positions are `joints`: per joint its
    /// effort as a share of the servo's torque (empty when none).
    fn grasps(
        &self,
        grasps: Vec<(String, f64)>,
        joints: &[Option<(f64, Option<f64>)>],
    ) -> Result<Vec<Option<f64>>, TargetError> {
        if grasps.is_empty() {
            return Ok(Vec::new());
        }
        let mut out = vec![None; self.names.len()];
        for (i, effort) in self.indexed(Joints::Named(grasps))? {
            let refuse = |why| TargetError::Grasp {
                joint: self.names[i].clone(),
                why,
            };
            if !(effort.is_finite() && effort > 0.0 && effort <= 100.0) {
                return Err(refuse(
                    "its effort is a percentage of the servo's torque, above 0 and at most 100",
                ));
            }
            if self.limits[i].max_position <= self.limits[i].min_position {
                return Err(refuse("it has no range to close in (a wheel)"));
            }
            if joints.get(i).is_some_and(Option::is_some) {
                return Err(refuse("the same target gives it a position"));
            }
            out[i] = Some(effort / 100.0);
        }
        Ok(out)
    }

    fn check(&self, target: LiveTarget) -> Result<(Checked, usize), TargetError> {
        let n = self.names.len();
        if !target.stamp.is_finite() {
            return Err(TargetError::NotFinite {
                joint: "stamp".into(),
            });
        }
        let given = self.indexed(target.joints)?;
        if let Some(v) = &target.velocities {
            if v.len() != given.len() {
                return Err(TargetError::WrongLength {
                    expected: given.len(),
                    actual: v.len(),
                });
            }
        }
        let mut joints = vec![None; n];
        let mut clamped = 0;
        for (k, &(i, q)) in given.iter().enumerate() {
            let v = target.velocities.as_ref().and_then(|v| v.get(k).copied());
            if !q.is_finite() || v.is_some_and(|v| !v.is_finite()) {
                return Err(TargetError::NotFinite {
                    joint: self.names[i].clone(),
                });
            }
            let l = &self.limits[i];
            let c = q.clamp(l.min_position, l.max_position);
            if c != q {
                clamped += 1;
            }
            joints[i] = Some((c, v));
        }
        let grasps = self.grasps(target.grasps, &joints)?;
        Ok((
            Checked {
                stamp: target.stamp,
                joints,
                grasps,
                taken: target.taken,
                chunk: None,
            },
            clamped,
        ))
    }
}
