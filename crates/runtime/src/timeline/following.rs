//! The timeline's live following: a run with no path, targets, events.

use super::*;

impl Timeline {
    /// A timeline with no path: the joints hold at `present` (rad) and
    /// follow live targets once they come.
    pub fn live(limits: Vec<JointLimits>, present: &[f64], target_timeout: f64) -> Self {
        let from: Vec<JointState> = present.iter().map(|&p| JointState::at_rest(p)).collect();
        let path = LivePath::new(limits.clone(), &from, 0.0, target_timeout);
        let mut tl = Timeline::empty(limits);
        tl.target_timeout = target_timeout;
        tl.stays = true;
        tl.segments
            .push(Segment::new(0.0, Kind::Live, Path::Live(Box::new(path))));
        tl
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

    /// Begins the cycle of time `t` (s since the start of the run): targets
    /// taken in from now on arrive at `t`, and live following times out by
    /// it. Called once a cycle, before anything else of the timeline.
    pub fn begin_cycle(&mut self, t: f64) {
        self.now = t;
        for seg in &mut self.segments {
            if let Path::Live(live) = &mut seg.path {
                live.begin_cycle(t);
            }
        }
    }

    /// Follows `target`, arrived in the cycle begun last (switching from
    /// the path to live following at the horizon if need be). Returns
    /// false when the run is ending (stopping or holding for good): the
    /// target is ignored.
    pub fn target(&mut self, target: &Checked) -> bool {
        let now = self.now;
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
        live.set_wheels(&self.wheels);
        live.begin_cycle(now);
        live.target(target, now);
        self.pending = None;
        self.push(Segment::new(x, Kind::Live, Path::Live(Box::new(live))));
        true
    }

    /// Hands `counters` the envelope figures of the live following, if it
    /// runs.
    pub fn envelopes(&self, counters: &crate::target::TargetCounts) {
        if let Some(Segment {
            path: Path::Live(live),
            ..
        }) = self.segments.last()
        {
            counters.envelopes(live.envelopes());
        }
    }

    /// What the live following did since last asked, if it runs.
    pub fn take_event(&mut self) -> Option<LiveEvent> {
        match self.segments.last_mut().map(|s| &mut s.path) {
            Some(Path::Live(live)) => live.take_event(),
            _ => None,
        }
    }
}
