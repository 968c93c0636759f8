//! Live targets: joint positions sent to a running loop while it runs (a
//! policy, a leader arm, another program), which the loop follows with a
//! jerk-limited step every cycle (see [`crate::live`]).
//!
//! A [`TargetSender`] checks each [`Target`] before it reaches the loop:
//! a value that is not finite, an unknown joint or the wrong number of
//! joints is refused ([`TargetError`], counted); a position outside its
//! joint's limits is clamped (counted). Targets travel on a bounded
//! channel; the loop takes every target waiting at the start of a cycle.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crossbeam_channel::Sender;
use serde::Serialize;
use servobus_trajectory::JointLimits;

use crate::report::Quantiles;
use crate::stats::Histogram;

/// The joints of a target.
#[derive(Debug, Clone, PartialEq)]
enum Joints {
    /// Every joint, in the robot's joint order.
    All(Vec<f64>),
    /// Some joints, by name; the others keep their targets.
    Named(Vec<(String, f64)>),
}

/// Joint positions for a running loop to go to, in radians, stamped with
/// the time they were taken (seconds on any clock the sender keeps: only
/// differences between stamps and their arrival matter).
#[derive(Debug, Clone, PartialEq)]
pub struct Target {
    stamp: f64,
    joints: Joints,
    velocities: Option<Vec<f64>>,
    taken: Option<Instant>,
}

impl Target {
    /// Every joint's position, in the robot's joint order (rad).
    pub fn all(stamp: f64, positions: Vec<f64>) -> Self {
        Target {
            stamp,
            joints: Joints::All(positions),
            velocities: None,
            taken: None,
        }
    }

    /// Some joints' positions by name (rad); the others keep their targets.
    pub fn named(stamp: f64, joints: Vec<(String, f64)>) -> Self {
        Target {
            stamp,
            joints: Joints::Named(joints),
            velocities: None,
            taken: None,
        }
    }

    /// The target's velocities (rad/s), one per joint given, in the same
    /// order; without them the loop estimates them from the stamps.
    pub fn with_velocities(mut self, velocities: Vec<f64>) -> Self {
        self.velocities = Some(velocities);
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
    pub taken: Option<Instant>,
}

/// The longest target latency the report's histogram holds.
const LATENCY_SPAN: Duration = Duration::from_millis(500);

/// The counts of a run's targets.
#[derive(Debug)]
pub(crate) struct Counters {
    received: AtomicU64,
    clamped: AtomicU64,
    refused: AtomicU64,
    timeouts: AtomicU64,
    resumes: AtomicU64,
    followed: AtomicU64,
    /// From a target's taking to the goals on the wire. Made with the
    /// counters, before the run starts: the loop only records into it.
    latency: Mutex<Histogram>,
}

impl Default for Counters {
    fn default() -> Self {
        Counters {
            received: AtomicU64::default(),
            clamped: AtomicU64::default(),
            refused: AtomicU64::default(),
            timeouts: AtomicU64::default(),
            resumes: AtomicU64::default(),
            followed: AtomicU64::default(),
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

impl Counters {
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
        };
        (r.received > 0 || get(&self.followed) > 0).then_some(r)
    }
}

/// What happened to a run's live targets (in the [`Report`](crate::Report)
/// of a run that followed targets).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
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
    /// From the taking of a target ([`Target::taken_at`]) to the first
    /// goals sent after it, ms, when targets said when they were taken.
    pub latency_ms: Option<Quantiles>,
}

/// A sender of live targets to a run (cheap to clone).
#[derive(Debug, Clone)]
pub struct TargetSender {
    tx: Sender<Arc<Checked>>,
    names: Arc<Vec<String>>,
    limits: Arc<Vec<JointLimits>>,
    counters: Arc<Counters>,
}

impl TargetSender {
    pub(crate) fn new(
        tx: Sender<Arc<Checked>>,
        names: Vec<String>,
        limits: Vec<JointLimits>,
        counters: Arc<Counters>,
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
    pub fn send(&self, target: Target) -> Result<usize, TargetError> {
        self.counters.received.fetch_add(1, Ordering::Relaxed);
        let checked = self.check(target).inspect_err(|_| {
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

    fn check(&self, target: Target) -> Result<(Checked, usize), TargetError> {
        let n = self.names.len();
        if !target.stamp.is_finite() {
            return Err(TargetError::NotFinite {
                joint: "stamp".into(),
            });
        }
        let given: Vec<(usize, f64)> = match target.joints {
            Joints::All(p) if p.len() != n => {
                return Err(TargetError::WrongLength {
                    expected: n,
                    actual: p.len(),
                })
            }
            Joints::All(p) => p.into_iter().enumerate().collect(),
            Joints::Named(named) => named
                .into_iter()
                .map(
                    |(name, q)| match self.names.iter().position(|x| *x == name) {
                        Some(i) => Ok((i, q)),
                        None => Err(TargetError::UnknownJoint(name)),
                    },
                )
                .collect::<Result<_, _>>()?,
        };
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
        Ok((
            Checked {
                stamp: target.stamp,
                joints,
                taken: target.taken,
            },
            clamped,
        ))
    }
}
