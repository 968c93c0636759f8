//! The timeline's live following: a run with no path, targets, events.

use super::*;

impl Timeline {
    /// A timeline with no path: the joints hold at `present` (rad) and
    /// follow live targets once they come.
    pub fn live(limits: Vec<JointLimits>, present: &[f64], target_timeout: f64) -> Self {
        let from: Vec<JointState> = present.iter().map(|&p| JointState::at_rest(p)).collect();
        let n = limits.len();
        let path = LivePath::new(limits.clone(), &from, 0.0, target_timeout);
        Timeline {
            live_limits: limits.clone(),
            limits,
            segments: vec![Segment::new(0.0, Kind::Live, Path::Live(Box::new(path)))],
            pending: None,
            horizon: 0.0,
            ramp: 0.05,
            scratch: vec![JointState::default(); n],
            over_since: None,
            approach: Duration::ZERO,
            now: 0.0,
            target_timeout,
        }
    }

    /// Sets how long live targets may fail to come before the joints stop,
    /// and the limits they are followed within (those of the path, or
    /// narrower).
    pub fn set_live(&mut self, timeout: f64, limits: Vec<JointLimits>) {
        self.target_timeout = timeout;
        if limits.len() == self.limits.len() {
            self.live_limits = limits;
        }
    }

    /// Sets the time of the cycle being run.
    pub fn set_now(&mut self, t: f64) {
        self.now = t;
    }

    /// Follows `target`, arrived in the cycle at `now` (switching from the
    /// path to live following at the horizon if need be). Returns false
    /// when the run is ending (stopping or holding for good): the target
    /// is ignored.
    pub fn target(&mut self, target: &Checked, now: f64) -> bool {
        match self.segments.last_mut() {
            Some(Segment {
                path: Path::Live(live),
                ..
            }) => {
                live.target(target, now);
                return true;
            }
            Some(s) if matches!(s.kind, Kind::Stop | Kind::Hold { last: true }) => return false,
            _ => {}
        }
        let st = self.state_at_horizon();
        let x = self.horizon;
        let mut live = LivePath::new(self.live_limits.clone(), &st, x, self.target_timeout);
        live.target(target, now);
        self.pending = None;
        self.push(Segment::new(x, Kind::Live, Path::Live(Box::new(live))));
        true
    }

    /// What the live following did since last asked, if it runs.
    pub fn take_event(&mut self) -> Option<LiveEvent> {
        match self.segments.last_mut().map(|s| &mut s.path) {
            Some(Path::Live(live)) => live.take_event(),
            _ => None,
        }
    }
}
