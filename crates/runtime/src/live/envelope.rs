//! How far a joint's commanded path went beyond the targets it was given:
//! the envelope of the targets received in the last [`WINDOW`] s (their
//! least and greatest position, and where the joint was when the oldest
//! of them came, for the way from there to them), and the stopping
//! allowance of each excursion beyond it.
//!
//! A follower that keeps up with a moving target cannot stop at once when
//! the targets turn back: it goes on by its quickest stop from the state
//! it had (its speed, acceleration and the joint's jerk limit). That
//! distance, taken from the commanded state in the cycle the excursion
//! began, is the excursion's allowance; anything beyond it is overshoot
//! the follower chose, and is reported as such.

use servobus_trajectory::{stop_position, JointLimits, JointState};

/// The time targets count toward the envelope, s.
pub const WINDOW: f64 = 0.5;

/// Arrivals kept per joint (each a target, or a chunk's range): more than
/// a 100 Hz stream sends in [`WINDOW`].
const KEPT: usize = 64;

/// What one joint's following did against its envelope.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct EnvelopeReport {
    /// The largest distance the commanded path went beyond the envelope of
    /// the last 0.5 s of targets (rad).
    pub overshoot: f64,
    /// The stopping distance its limits made unavoidable in that
    /// excursion (rad): from the commanded state where it began.
    pub allowance: f64,
    /// The largest overshoot beyond its excursion's allowance (rad): 0
    /// when the follower never went further than it had to.
    pub beyond_allowance: f64,
}

/// One joint's envelope and excursions (see the module docs).
#[derive(Debug, Clone)]
pub(super) struct Envelope {
    /// `(arrival, least, greatest, commanded position then)` of recent
    /// targets, a ring.
    seen: [(f64, f64, f64, f64); KEPT],
    head: usize,
    len: usize,
    /// The allowance of the excursion under way.
    excursion: Option<f64>,
    /// The commanded state of the last cycle.
    last: JointState,
    report: EnvelopeReport,
}

impl Envelope {
    pub fn new(state: JointState) -> Self {
        Envelope {
            seen: [(0.0, 0.0, 0.0, 0.0); KEPT],
            head: 0,
            len: 0,
            excursion: None,
            last: state,
            report: EnvelopeReport::default(),
        }
    }

    /// Targets from `least` to `greatest` arrived at `x`.
    pub fn arrived(&mut self, x: f64, least: f64, greatest: f64) {
        self.head = (self.head + 1) % KEPT;
        self.seen[self.head] = (x, least, greatest, self.last.position);
        self.len = (self.len + 1).min(KEPT);
    }

    /// The envelope at `x`, if a target arrived in the window before it.
    fn range(&self, x: f64) -> Option<(f64, f64)> {
        let mut out: Option<(f64, f64)> = None;
        let mut then = None;
        for k in 0..self.len {
            let (t, lo, hi, c) = self.seen[(self.head + KEPT - k) % KEPT];
            if x - t > WINDOW {
                break;
            }
            then = Some(c);
            out = Some(out.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))));
        }
        out.zip(then).map(|((lo, hi), c)| (lo.min(c), hi.max(c)))
    }

    /// The commanded state `state` of the cycle at `x`.
    pub fn commanded(&mut self, lim: &JointLimits, x: f64, state: JointState) {
        let excess = self.range(x).map_or(0.0, |(lo, hi)| {
            (state.position - hi).max(lo - state.position).max(0.0)
        });
        if excess > 0.0 {
            let last = self.last;
            let allowance = *self
                .excursion
                .get_or_insert_with(|| (stop_position(lim, &last) - last.position).abs());
            let r = &mut self.report;
            if excess > r.overshoot {
                r.overshoot = excess;
                r.allowance = allowance;
            }
            r.beyond_allowance = r.beyond_allowance.max(excess - allowance);
        } else {
            self.excursion = None;
        }
        self.last = state;
    }

    pub fn report(&self) -> EnvelopeReport {
        self.report
    }
}
