//! The robot-wide commanded path as a function of time: the main path with
//! its time scale (pause/resume), the approach to its start, transitions,
//! stops and holds, joined end to end so that position and velocity are
//! continuous across every change.
//!
//! Time `x` is seconds since the start of the run, on the cycle timeline:
//! goals are sampled at `x = t + lead`, the reference the joints are judged
//! against at `x` = the time of the reading. Every change starts at the
//! *horizon*, the latest time already commanded, so that no bus ever
//! steps back along a path it has already been sent.
//!
//! Steady-state sampling allocates nothing; each change (a command, a
//! fault reaction) plans a short path once, which allocates.
//!
//! Wheel joints ([`Timeline::set_wheels`]) have no position on the path:
//! their entries in a sampled state mean nothing, and their target speeds
//! come from [`Timeline::wheel_targets`] instead: a live target's speed
//! while live targets are followed, 0 under any other segment (a played
//! path, a stop, a hold), paused or timed out.

use std::sync::Arc;
use std::time::Duration;

use servobus_trajectory::{self as traj, Cursor, JointLimits, JointState, Trajectory};

use crate::error::RunError;
use crate::live::{LiveEvent, LivePath};
use crate::target::Checked;

mod following;
mod scale;

use scale::{pause_ramp, Scale};

/// The default time live targets may fail to come before the joints stop, s.
pub(crate) const DEFAULT_TARGET_TIMEOUT: f64 = 0.25;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    Approach,
    Main,
    Transition,
    Stop,
    /// Following live targets.
    Live,
    /// Waiting for `Play` (not final) or a fault reaction (final).
    Hold {
        last: bool,
    },
}

#[derive(Debug, Clone)]
enum Path {
    /// Sampled at `x - start`.
    Plain(Arc<Trajectory>),
    /// Sampled at `tau(x)`.
    Scaled(Arc<Trajectory>, Scale),
    Fixed(Vec<f64>),
    Live(Box<LivePath>),
}

#[derive(Debug, Clone)]
struct Segment {
    start: f64,
    kind: Kind,
    path: Path,
    cmd: Cursor,
    reference: Cursor,
}

impl Segment {
    fn new(start: f64, kind: Kind, path: Path) -> Self {
        let (cmd, reference) = match &path {
            Path::Plain(t) | Path::Scaled(t, _) => (t.cursor(), t.cursor()),
            Path::Fixed(_) | Path::Live(_) => (Cursor::default(), Cursor::default()),
        };
        Segment {
            start,
            kind,
            path,
            cmd,
            reference,
        }
    }

    /// The path at `x`.
    fn sample(&mut self, x: f64, which: Which, out: &mut [JointState]) {
        let cursor = match which {
            Which::Cmd => &mut self.cmd,
            Which::Ref => &mut self.reference,
        };
        match &mut self.path {
            Path::Live(live) => match which {
                Which::Cmd => live.sample_cmd(x, out),
                Which::Ref => live.sample_ref(x, out),
            },
            Path::Plain(t) => t.sample_with(cursor, x - self.start, out),
            Path::Scaled(t, scale) => {
                let (tau, s, ds) = scale.at(x);
                t.sample_with(cursor, tau, out);
                for o in out.iter_mut() {
                    o.acceleration = o.acceleration * s * s + o.velocity * ds;
                    o.velocity *= s;
                }
            }
            Path::Fixed(p) => {
                for (o, &p) in out.iter_mut().zip(p.iter()) {
                    *o = JointState::at_rest(p);
                }
            }
        }
    }

    /// Whether the segment's path is over at `x` (a final hold is over once
    /// it has begun).
    fn over(&self, x: f64) -> bool {
        match (&self.path, self.kind) {
            (Path::Plain(t), _) => x - self.start >= t.duration(),
            (Path::Scaled(t, scale), _) => scale.at(x).0 >= t.duration(),
            (Path::Fixed(_), Kind::Hold { last }) => last && x >= self.start,
            (Path::Fixed(_), _) | (Path::Live(_), _) => false,
        }
    }
}

#[derive(Debug, Clone, Copy)]
enum Which {
    Cmd,
    Ref,
}

/// See the module documentation.
#[derive(Debug, Clone)]
pub(crate) struct Timeline {
    limits: Vec<JointLimits>,
    segments: Vec<Segment>,
    /// The main path waiting for `Play`.
    pending: Option<Arc<Trajectory>>,
    /// Latest time sampled for commands.
    horizon: f64,
    /// Length of a pause or resume ramp, s.
    ramp: f64,
    /// Scratch state for planning changes.
    scratch: Vec<JointState>,
    /// When the last segment was found over (for the settling time).
    over_since: Option<f64>,
    /// How long the approach to the main path's start takes, as planned.
    approach: Duration,
    /// The time of the cycle being run ([`Timeline::begin_cycle`]): live
    /// targets arrive and time out by it.
    now: f64,
    /// How long live targets may fail to come before the joints stop, s.
    target_timeout: f64,
    /// The limits live targets are followed within.
    live_limits: Vec<JointLimits>,
    /// A live run: a path played in it gives way to a hold when it ends,
    /// and the run goes on (for more targets or paths) until stopped.
    stays: bool,
    /// Which joints are wheels (robot order).
    wheels: Vec<bool>,
    /// The grasps the played path makes, by its time.
    grasps: Vec<crate::grasp::GraspAt>,
    /// The furthest time on the played path the grasps were judged at.
    grasp_tau: f64,
}

/// Limits scaled by `f` (positions unchanged).
fn scaled(limits: &[JointLimits], f: f64) -> Vec<JointLimits> {
    limits
        .iter()
        .map(|l| {
            JointLimits::new(
                l.max_velocity * f,
                l.max_acceleration * f,
                l.max_jerk.map(|j| j * f),
            )
            .with_positions(l.min_position, l.max_position)
        })
        .collect()
}

impl Timeline {
    /// The one constructor: no segment yet, the pause ramp of `limits`,
    /// live targets followed within `limits` with the default timeout.
    fn empty(limits: Vec<JointLimits>) -> Self {
        let n = limits.len();
        Timeline {
            ramp: pause_ramp(&limits),
            live_limits: limits.clone(),
            limits,
            segments: Vec::with_capacity(8),
            pending: None,
            horizon: 0.0,
            scratch: vec![JointState::default(); n],
            over_since: None,
            approach: Duration::ZERO,
            now: 0.0,
            target_timeout: DEFAULT_TARGET_TIMEOUT,
            stays: false,
            wheels: vec![false; n],
            grasps: Vec::new(),
            grasp_tau: f64::NEG_INFINITY,
        }
    }

    /// The timeline of a run: from `present` (rad, at rest) to the start of
    /// `main` (an approach at `approach` of the limits, when given and the
    /// joints are more than `tolerance` rad away), then `main` at once or,
    /// without `autoplay`, once [`Timeline::play`] is called.
    pub fn new(
        limits: Vec<JointLimits>,
        main: Arc<Trajectory>,
        present: &[f64],
        approach: Option<f64>,
        autoplay: bool,
        tolerance: f64,
    ) -> Result<Self, RunError> {
        let n = limits.len();
        let mut tl = Timeline::empty(limits);
        let mut start = vec![JointState::default(); n];
        main.sample(0.0, &mut start);
        let target: Vec<f64> = start.iter().map(|s| s.position).collect();
        let far = present
            .iter()
            .zip(&target)
            .any(|(p, q)| (p - q).abs() > tolerance);
        let mut t0 = 0.0;
        match approach {
            Some(f) if far => {
                let from: Vec<JointState> =
                    present.iter().map(|&p| JointState::at_rest(p)).collect();
                let lim = scaled(&tl.limits, f.clamp(0.01, 1.0));
                let path = traj::retarget(&lim, &from, &target).map_err(|source| {
                    RunError::Trajectory {
                        what: "approach to the start",
                        source,
                    }
                })?;
                t0 = path.duration();
                tl.approach = Duration::from_secs_f64(t0);
                tl.segments.push(Segment::new(
                    0.0,
                    Kind::Approach,
                    Path::Plain(Arc::new(path)),
                ));
            }
            _ => {}
        }
        if autoplay {
            tl.segments.push(Segment::new(
                t0,
                Kind::Main,
                Path::Scaled(main, Scale::constant(t0)),
            ));
        } else {
            tl.segments.push(Segment::new(
                t0,
                Kind::Hold { last: false },
                Path::Fixed(target),
            ));
            tl.pending = Some(main);
        }
        Ok(tl)
    }

    /// How long the planned approach to the main path's start takes (zero
    /// without one): the main path begins then.
    pub fn approach(&self) -> Duration {
        self.approach
    }

    /// The index of the segment in force at `x` (the first before any
    /// starts).
    fn index_at(&self, x: f64) -> usize {
        self.segments
            .iter()
            .rposition(|s| s.start <= x)
            .unwrap_or(0)
    }

    fn active(&mut self, x: f64) -> Option<&mut Segment> {
        let i = self.index_at(x);
        self.segments.get_mut(i)
    }

    /// The commanded state at `x` (advances the horizon).
    pub fn sample_cmd(&mut self, x: f64, out: &mut [JointState]) {
        self.horizon = self.horizon.max(x);
        if let Some(s) = self.active(x) {
            s.sample(x, Which::Cmd, out);
        }
    }

    /// Marks the wheel joints (`wheels[j]`, robot order): their targets
    /// are speeds ([`Timeline::wheel_targets`]).
    pub fn set_wheels(&mut self, wheels: Vec<bool>) {
        for seg in &mut self.segments {
            if let Path::Live(live) = &mut seg.path {
                live.set_wheels(&wheels);
            }
        }
        self.wheels = wheels;
    }

    /// The efforts of the grasps being made at `x` into `out` (robot
    /// order; `None` for a joint making none): those of the live targets
    /// while they are followed (a timeout or a pause keeps them: the
    /// gripper holds on), none under any other segment.
    ///
    /// On the played path, those of its schedule ([`Timeline::set_grasps`])
    /// at the path's time; after it (a stop, a hold) those it ended with.
    pub fn grasp_efforts(&mut self, x: f64, out: &mut [Option<f64>]) {
        out.fill(None);
        if let Some(live) = self.live_at(x) {
            live.grasp_efforts(out);
            return;
        }
        if self.grasps.is_empty() {
            return;
        }
        if let Some(seg) = self.segment_at(x) {
            let tau = match (&seg.path, seg.kind) {
                (Path::Scaled(_, scale), Kind::Main) => Some(scale.at(x).0),
                (Path::Plain(_), Kind::Main) => Some(x - seg.start),
                _ => None,
            };
            if let Some(tau) = tau {
                self.grasp_tau = self.grasp_tau.max(tau);
            }
        }
        crate::grasp::efforts_at(&self.grasps, self.grasp_tau, out);
    }

    /// The grasps the played path makes, at its own times (sorted here).
    pub fn set_grasps(&mut self, mut grasps: Vec<crate::grasp::GraspAt>) {
        grasps.sort_by(|a, b| a.at_s.total_cmp(&b.at_s));
        self.grasps = grasps;
    }

    /// The segment in force at `x` (the first before any starts).
    fn segment_at(&self, x: f64) -> Option<&Segment> {
        self.segments.get(self.index_at(x))
    }

    /// The live path in force at `x`, if the segment then is one.
    fn live_at(&self, x: f64) -> Option<&LivePath> {
        match self.segment_at(x).map(|s| &s.path) {
            Some(Path::Live(live)) => Some(live),
            _ => None,
        }
    }

    /// The wheels' target speeds (rad/s) at `x` into `out` (robot order;
    /// position joints' entries are left as they are): the live targets'
    /// while they are followed, else 0. Sampled after
    /// [`sample_cmd`](Self::sample_cmd) at the same `x`, which judges the
    /// live timeout.
    pub fn wheel_targets(&self, x: f64, out: &mut [f64]) {
        for (o, _) in out.iter_mut().zip(&self.wheels).filter(|(_, &w)| w) {
            *o = 0.0;
        }
        if let Some(live) = self.live_at(x) {
            live.wheel_speeds(out);
        }
    }

    /// The reference (where the joints should be) at `x`.
    pub fn sample_ref(&mut self, x: f64, out: &mut [JointState]) {
        if let Some(s) = self.active(x) {
            s.sample(x, Which::Ref, out);
        }
    }

    /// Forgets segments no longer needed by references at or after `x`.
    pub fn prune(&mut self, x: f64) {
        while self.segments.len() >= 2 && self.segments[1].start <= x {
            self.segments.remove(0);
        }
    }

    /// Whether the run's path is over at reference time `x`, with the
    /// final position held for `settle` s when the main path completed.
    pub fn finished(&mut self, x: f64, settle: f64) -> bool {
        let Some(last) = self.segments.last() else {
            return true;
        };
        if last.start > x || !last.over(x) {
            self.over_since = None;
            return false;
        }
        if self.stays && last.kind == Kind::Main {
            // A live run holds where the path ended, and goes on.
            let mut st = std::mem::take(&mut self.scratch);
            if let Some(last) = self.segments.last_mut() {
                last.sample(x, Which::Cmd, &mut st);
            }
            let end = st.iter().map(|s| s.position).collect();
            self.scratch = st;
            self.push(Segment::new(
                x,
                Kind::Hold { last: false },
                Path::Fixed(end),
            ));
            return false;
        }
        let since = *self.over_since.get_or_insert(x);
        match last.kind {
            Kind::Main => x - since >= settle,
            _ => true,
        }
    }

    /// The kind of the last segment (what the run is heading for).
    pub fn last_kind(&self) -> Option<Kind> {
        self.segments.last().map(|s| s.kind)
    }

    /// The kind of segment active at `x`.
    pub fn kind_at(&self, x: f64) -> Option<Kind> {
        self.segment_at(x).map(|s| s.kind)
    }

    /// The latest commanded time.
    pub fn horizon(&self) -> f64 {
        self.horizon
    }

    fn push(&mut self, seg: Segment) {
        // A change replaces everything planned after its start.
        while self.segments.last().is_some_and(|s| s.start > seg.start) {
            self.segments.pop();
        }
        self.over_since = None;
        self.segments.push(seg);
    }

    fn state_at_horizon(&mut self) -> Vec<JointState> {
        let x = self.horizon;
        let mut st = std::mem::take(&mut self.scratch);
        if let Some(s) = self.active(x) {
            s.sample(x, Which::Cmd, &mut st);
        }
        let out = st.clone();
        self.scratch = st;
        out
    }

    /// Starts the pending main path (no-op when none waits; resumes when
    /// paused).
    pub fn play(&mut self) {
        match self.pending.take() {
            Some(main) => {
                // Played during the approach, the path starts where the
                // approach ends: it leads to the path's start.
                let x = match self.segments.last() {
                    Some(s) if s.kind == (Kind::Hold { last: false }) => {
                        let x = s.start.max(self.horizon);
                        self.segments.pop();
                        x
                    }
                    _ => self.horizon,
                };
                self.push(Segment::new(
                    x,
                    Kind::Main,
                    Path::Scaled(main, Scale::constant(x)),
                ));
            }
            None => self.set_speed(1.0),
        }
    }

    /// Ramps the main path's time scale to `target` (0: pause, 1: resume).
    /// Following live targets, 0 stops and holds, anything else follows
    /// again.
    pub fn set_speed(&mut self, target: f64) {
        let x = self.horizon;
        let ramp = self.ramp;
        if let Some(seg) = self.segments.last_mut() {
            match &mut seg.path {
                Path::Scaled(_, scale) => *scale = scale.ramp_to(x.max(seg.start), target, ramp),
                Path::Live(live) => live.pause(target == 0.0),
                _ => {}
            }
        }
        self.over_since = None;
    }

    /// Stops along a jerk-limited path from the commanded state, then holds.
    pub fn stop(&mut self) -> Result<(), RunError> {
        let st = self.state_at_horizon();
        let path = traj::stop(&self.limits, &st).map_err(|source| RunError::Trajectory {
            what: "stop",
            source,
        })?;
        let x = self.horizon;
        self.pending = None;
        self.push(Segment::new(x, Kind::Stop, Path::Plain(Arc::new(path))));
        Ok(())
    }

    /// Holds `positions` (rad) from the horizon on; the run ends there.
    pub fn hold(&mut self, positions: Vec<f64>) {
        let x = self.horizon;
        self.pending = None;
        self.push(Segment::new(
            x,
            Kind::Hold { last: true },
            Path::Fixed(positions),
        ));
    }

    /// Replaces the path: a jerk-limited transition from the commanded
    /// state to `main`'s start, then `main`.
    pub fn replace(&mut self, main: Arc<Trajectory>) -> Result<(), RunError> {
        let n = self.limits.len();
        if main.joints() != n {
            return Err(RunError::NewPathJoints {
                expected: n,
                given: main.joints(),
            });
        }
        let st = self.state_at_horizon();
        let mut start = vec![JointState::default(); n];
        main.sample(0.0, &mut start);
        let target: Vec<f64> = start.iter().map(|s| s.position).collect();
        let path =
            traj::retarget(&self.limits, &st, &target).map_err(|source| RunError::Trajectory {
                what: "transition to the new path",
                source,
            })?;
        let x = self.horizon;
        let x1 = x + path.duration();
        self.pending = None;
        self.push(Segment::new(
            x,
            Kind::Transition,
            Path::Plain(Arc::new(path)),
        ));
        self.push(Segment::new(
            x1,
            Kind::Main,
            Path::Scaled(main, Scale::constant(x1)),
        ));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_approach_is_when_the_main_path_begins() {
        let lim = vec![JointLimits::new(2.0, 8.0, Some(40.0))];
        let main = traj::retarget(&lim, &[JointState::at_rest(0.0)], &[1.0]).expect("a path");
        let main = Arc::new(main);
        let plan = |from| Timeline::new(lim.clone(), main.clone(), &[from], Some(0.25), true, 0.01);
        let tl = plan(-1.0).expect("an approach");
        let t0 = tl.approach().as_secs_f64();
        // 2 rad at a quarter of the limits take longer than the path's 1 rad at full.
        assert!(t0 > main.duration(), "{t0}");
        assert_eq!(tl.kind_at(t0 - 1e-3), Some(Kind::Approach));
        assert_eq!(tl.kind_at(t0 + 1e-3), Some(Kind::Main));
        let there = plan(0.0).expect("no approach");
        assert_eq!(
            (there.approach(), there.kind_at(0.0)),
            (Duration::ZERO, Some(Kind::Main))
        );
    }
}
