//! The body a simulated servo drives: how its horn is mounted on the joint,
//! the joint's mechanical stops, a hand that moves it, and the truth of
//! where the joint physically is.
//!
//! Without a body a simulated servo is a bare shaft in its sensor frame.
//! With one, the joint has a physical angle in degrees (0 at the joint's
//! physical zero) and the servo's raw sensor reads
//!
//! ```text
//! raw = (zero_tick + direction * angle * ticks_per_deg) mod resolution
//! present position = (raw - homing offset) mod resolution
//! ```
//!
//! so a horn fitted anywhere on the turn shows up as it does on a real
//! robot: ranges that cross the 4095 -> 0 seam, reversed directions.
//!
//! The body follows the shaft's sensor ticks step by step and unwraps them
//! into the joint angle (a step moves far less than half a turn), so a joint
//! that crosses the seam keeps a continuous angle. Stops clamp the angle and
//! load the servo; the hand sets the angle of a joint whose torque is off and
//! pushes on one whose torque is on, and may put an object in the joint's
//! way ([`HandObject`]: what a gripper closes on).

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use servobus_protocol::registers::Model;

mod object;

use object::Contact;
pub use object::{HandObject, DEFAULT_STIFFNESS, GIVE_SPEED_DEG_S, MAX_STIFFNESS};

/// The shortest signed way from `b` to `a` on a sensor of `turn` ticks a
/// turn, in `[-turn / 2, turn / 2)`: how far a full-turn sensor moved
/// between two readings that may lie either side of the seam.
///
/// ```
/// use servobus_sim::body::turn_delta;
/// assert_eq!(turn_delta(10.0, 4090.0, 4096.0), 16.0);
/// assert_eq!(turn_delta(4090.0, 10.0, 4096.0), -16.0);
/// assert_eq!(turn_delta(300.0, 100.0, 4096.0), 200.0);
/// ```
pub fn turn_delta(a: f64, b: f64, turn: f64) -> f64 {
    (a - b + turn / 2.0).rem_euclid(turn) - turn / 2.0
}

/// How a servo's horn is fitted to its joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mount {
    /// The raw sensor tick (homing offset 0) when the joint is at its
    /// physical zero.
    pub zero_tick: f64,
    /// +1 when rising ticks turn the joint positive, -1 when they turn it
    /// negative.
    pub direction: f64,
    /// Mechanical stops `[min, max]` in physical degrees, if any: the joint
    /// blocks there and a servo pushing on it is loaded.
    pub stops: Option<[f64; 2]>,
}

impl Mount {
    /// A horn with `zero_tick` at the joint's zero, turning the joint
    /// positive with rising ticks (`reversed` false) or negative, no stops.
    pub fn new(zero_tick: f64, reversed: bool) -> Mount {
        Mount {
            zero_tick,
            direction: if reversed { -1.0 } else { 1.0 },
            stops: None,
        }
    }

    /// The same mounting with stops at `min_deg` and `max_deg`.
    #[must_use]
    pub fn with_stops(mut self, min_deg: f64, max_deg: f64) -> Mount {
        self.stops = Some([min_deg.min(max_deg), min_deg.max(max_deg)]);
        self
    }
}

/// One joint's part of a hand's path: angles in physical degrees at times
/// in seconds from the simulator's start, eased between keyframes
/// (minimum-jerk: the hand starts and stops each move with zero velocity
/// and acceleration).
///
/// Only the keyframes of this joint count: a hand file's keyframe that does
/// not name the joint is not one of them, so the joint eases from the
/// keyframe before it to the one after it as if it were not there. Before
/// its first keyframe and after its last the hand does not touch the joint
/// (a person lets go); in between it holds it on the path.
///
/// The hand may also put an object in the joint's way
/// ([`HandPath::with_object`]), there from the start whether or not the path
/// has keyframes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HandPath {
    keys: Vec<(f64, f64)>,
    object: Option<HandObject>,
}

impl HandPath {
    /// A path through `(time_s, angle_deg)` keyframes; they are sorted by
    /// time and non-finite ones are dropped.
    pub fn new(keys: impl IntoIterator<Item = (f64, f64)>) -> HandPath {
        let mut keys: Vec<(f64, f64)> = keys
            .into_iter()
            .filter(|(t, a)| t.is_finite() && a.is_finite())
            .collect();
        keys.sort_by(|a, b| a.0.total_cmp(&b.0));
        HandPath { keys, object: None }
    }

    /// The same path with `object` in the joint's way (see [`HandObject`]).
    #[must_use]
    pub fn with_object(mut self, object: HandObject) -> HandPath {
        self.object = Some(object);
        self
    }

    /// The object the hand puts in the joint's way, if any.
    pub fn object(&self) -> Option<HandObject> {
        self.object
    }

    /// The keyframes, sorted by time.
    pub fn keys(&self) -> &[(f64, f64)] {
        &self.keys
    }

    /// The time the hand takes hold of the joint, if it ever does.
    pub fn start_s(&self) -> Option<f64> {
        self.keys.first().map(|k| k.0)
    }

    /// Whether the hand holds the joint at `t` seconds.
    pub fn holds(&self, t: f64) -> bool {
        match (self.keys.first(), self.keys.last()) {
            (Some(a), Some(b)) => a.0 <= t && t <= b.0,
            _ => false,
        }
    }

    /// The hand's angle at `t`, while it holds the joint.
    pub fn angle_at(&self, t: f64) -> Option<f64> {
        if !self.holds(t) {
            return None;
        }
        let i = self.keys.partition_point(|k| k.0 <= t);
        let (t0, a0) = self.keys[i.saturating_sub(1)];
        let Some(&(t1, a1)) = self.keys.get(i) else {
            return Some(a0);
        };
        let s = ((t - t0) / (t1 - t0)).clamp(0.0, 1.0);
        let ease = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
        Some(a0 + (a1 - a0) * ease)
    }
}

/// One row of the truth: the time and every joint's physical angle.
#[derive(Debug, Clone, PartialEq)]
pub struct TruthRow {
    /// Seconds from the simulator's start.
    pub time_s: f64,
    /// Physical joint angles in degrees, in the recorder's column order.
    pub angles_deg: Vec<f64>,
}

#[derive(Debug)]
struct Table {
    names: Vec<String>,
    period: Duration,
    /// Index of the first sample still held in every column.
    base: u64,
    columns: Vec<Vec<f64>>,
}

/// A recorder of the physical joint angles of simulated servos, sampled on
/// a fixed grid (`time = k * period`) as their bodies move.
///
/// Cheap to clone: clones share the table. Each servo writes its own
/// column ([`SimServo::with_truth`](crate::SimServo::with_truth)); a row is
/// complete once every column has reached it.
#[derive(Debug, Clone)]
pub struct Truth {
    table: Arc<Mutex<Table>>,
}

impl Truth {
    /// A recorder of the joints `names` (the columns) every `period`
    /// (clamped to at least 1 ms).
    pub fn new(names: Vec<String>, period: Duration) -> Truth {
        let columns = vec![Vec::new(); names.len()];
        Truth {
            table: Arc::new(Mutex::new(Table {
                names,
                period: period.max(Duration::from_millis(1)),
                base: 0,
                columns,
            })),
        }
    }

    fn lock(&self) -> MutexGuard<'_, Table> {
        self.table.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The column names.
    pub fn names(&self) -> Vec<String> {
        self.lock().names.clone()
    }

    /// The sampling period.
    pub fn period(&self) -> Duration {
        self.lock().period
    }

    /// The CSV header: `time_s,<joint>,...`.
    pub fn csv_header(&self) -> String {
        let mut h = String::from("time_s");
        for n in &self.lock().names {
            h.push(',');
            h.push_str(n);
        }
        h
    }

    /// Every complete row still held (all of them unless
    /// [`Truth::take_rows`] was called).
    pub fn rows(&self) -> Vec<TruthRow> {
        let t = self.lock();
        complete_rows(&t)
    }

    /// The complete rows not taken before, removed from the recorder (for a
    /// writer that streams them to a file).
    pub fn take_rows(&self) -> Vec<TruthRow> {
        let mut t = self.lock();
        let rows = complete_rows(&t);
        let n = rows.len();
        for c in &mut t.columns {
            c.drain(..n.min(c.len()));
        }
        t.base += n as u64;
        rows
    }

    /// The physical angle of column `column` at `time`, interpolated
    /// between the samples around it.
    pub fn angle_at(&self, column: usize, time: Duration) -> Option<f64> {
        let t = self.lock();
        let c = t.columns.get(column)?;
        let k = time.as_secs_f64() / t.period.as_secs_f64() - t.base as f64;
        if k < 0.0 {
            return None;
        }
        let i = k.floor() as usize;
        let a = *c.get(i)?;
        let b = c.get(i + 1).copied().unwrap_or(a);
        Some(a + (b - a) * (k - i as f64))
    }

    /// Records the samples of `column` on the grid in `(t0, t1]` (and at
    /// `t0` itself when the column is empty at 0), the angle moving linearly
    /// from `a0` to `a1`.
    pub(crate) fn record(&self, column: usize, t0: f64, t1: f64, a0: f64, a1: f64) {
        let mut t = self.lock();
        let period = t.period.as_secs_f64();
        let base = t.base;
        let Some(c) = t.columns.get_mut(column) else {
            return;
        };
        loop {
            let k = base + c.len() as u64;
            let tk = k as f64 * period;
            if tk > t1 + 1e-12 {
                return;
            }
            let a = if t1 > t0 && tk > t0 {
                a0 + (a1 - a0) * ((tk - t0) / (t1 - t0))
            } else {
                a0
            };
            c.push(a);
        }
    }
}

fn complete_rows(t: &Table) -> Vec<TruthRow> {
    let n = t.columns.iter().map(Vec::len).min().unwrap_or(0);
    let period = t.period.as_secs_f64();
    (0..n)
        .map(|i| TruthRow {
            time_s: (t.base + i as u64) as f64 * period,
            angles_deg: t.columns.iter().map(|c| c[i]).collect(),
        })
        .collect()
}

/// How hard a hand pushes on a joint whose torque is on, as a fraction of
/// the servo's maximum torque: a person pushing a small arm's link, which a
/// healthy servo holds with a small deflection.
pub(crate) const HAND_PUSH: f64 = 0.3;
/// The distance, in degrees, between the hand's pose and the joint at which
/// the hand pushes with its full [`HAND_PUSH`].
const HAND_FULL_PUSH_DEG: f64 = 5.0;

/// The body of one servo: its mounting, the hand on it, the truth column it
/// writes, and the joint's physical angle.
#[derive(Debug, Clone)]
pub(crate) struct Body {
    pub mount: Mount,
    pub hand: Option<HandPath>,
    pub truth: Option<(Truth, usize)>,
    /// Physical angle, degrees.
    pub angle: f64,
    /// The sensor position the angle was last brought in line with.
    raw: f64,
    /// The servo's model: its sensor's resolution and range.
    model: &'static Model,
    /// The hand's object as this body met it (its side), once it has.
    contact: Option<Contact>,
    /// The time of the last [`Body::settle`], s.
    settled_at: Option<f64>,
}

impl Body {
    /// A body at physical `angle` for the sensor of a `model` servo.
    pub(crate) fn new(mount: Mount, angle: f64, model: &'static Model) -> Body {
        let mut b = Body {
            mount,
            hand: None,
            truth: None,
            angle,
            raw: 0.0,
            model,
            contact: None,
            settled_at: None,
        };
        b.angle = b.clamp_to_stops(angle);
        b.raw = b.raw_of(b.angle);
        b
    }

    /// The raw sensor position the body was last brought in line with.
    pub(crate) fn raw(&self) -> f64 {
        self.raw
    }

    /// Whether the sensor wraps at the seam (a full-turn sensor).
    pub(crate) fn full_turn(&self) -> bool {
        self.model.range_deg >= 360.0
    }

    /// Sensor ticks a turn (or over the sensor's range).
    fn resolution(&self) -> f64 {
        f64::from(self.model.resolution)
    }

    /// Sensor ticks per degree of joint motion.
    fn ticks_per_deg(&self) -> f64 {
        self.resolution() / self.model.range_deg
    }

    /// The sensor position (raw ticks, before the homing offset) of a
    /// physical angle.
    pub(crate) fn raw_of(&self, angle: f64) -> f64 {
        let t = self.mount.zero_tick + self.mount.direction * angle * self.ticks_per_deg();
        if self.full_turn() {
            t.rem_euclid(self.resolution())
        } else {
            t.clamp(0.0, self.resolution() - 1.0)
        }
    }

    fn clamp_to_stops(&self, angle: f64) -> f64 {
        match self.mount.stops {
            Some([lo, hi]) => angle.clamp(lo, hi),
            None => angle,
        }
    }

    /// Follows the sensor to `raw`: the nearest angle (within half a turn)
    /// that reads `raw`.
    pub(crate) fn follow(&mut self, raw: f64) {
        let d = if self.full_turn() {
            turn_delta(raw, self.raw, self.resolution())
        } else {
            raw - self.raw
        };
        self.angle += d / (self.mount.direction * self.ticks_per_deg());
        self.raw = raw;
    }

    /// Whether the joint rests on a stop and the servo pushes further into
    /// it (`push_ticks`: the sign of the servo's drive in sensor ticks).
    pub(crate) fn blocked_by_stop(&self, push_ticks: f64) -> bool {
        let Some([lo, hi]) = self.mount.stops else {
            return false;
        };
        let push = push_ticks * self.mount.direction;
        let eps = 1e-6;
        (self.angle <= lo + eps && push < 0.0) || (self.angle >= hi - eps && push > 0.0)
    }

    /// The load (fraction of maximum torque, positive towards lower ticks)
    /// with which the hand and its object push a torque-on joint at `t`.
    pub(crate) fn hand_load(&self, t: f64) -> f64 {
        let mut push = match self.hand.as_ref().and_then(|h| h.angle_at(t)) {
            Some(target) => {
                ((target - self.angle) / HAND_FULL_PUSH_DEG).clamp(-1.0, 1.0) * HAND_PUSH
            }
            None => 0.0,
        };
        if let Some(c) = self.contact_now() {
            push += c.push(self.angle);
        }
        -self.mount.direction * push
    }

    /// The hand's object as the body holds it: met at the present angle
    /// unless it was met before.
    fn contact_now(&self) -> Option<Contact> {
        let object = self.hand.as_ref()?.object()?;
        match self.contact {
            Some(c) if c.object == object => Some(c),
            _ => Some(Contact::new(object, self.angle)),
        }
    }

    /// Whether the hand holds the joint at any time in `[t0, t1]`.
    pub(crate) fn hand_active(&self, t0: f64, t1: f64) -> bool {
        self.hand.as_ref().is_some_and(|h| match h.keys().first() {
            Some(first) => h.holds(t0) || (t0 < first.0 && first.0 <= t1),
            None => false,
        })
    }

    /// The time the hand takes hold, when that is after `t`.
    pub(crate) fn hand_starts_after(&self, t: f64) -> Option<f64> {
        self.hand.as_ref()?.start_s().filter(|&s| s > t)
    }

    /// The angle the body should take at `t` after the shaft moved to
    /// `raw`: the shaft's own angle, or the hand's when it holds a torque-off
    /// joint, clamped to the stops and kept out of the hand's object as far
    /// as it gives way. Returns the new sensor position when the body
    /// overrides the shaft.
    pub(crate) fn settle(&mut self, raw: f64, t: f64, torque_on: bool) -> Option<f64> {
        // The object's side is decided where the joint is when it first
        // meets it (before this step's move).
        self.contact = self.contact_now();
        let before = self.angle;
        let dt = self.settled_at.map_or(0.0, |t0| t - t0);
        self.settled_at = Some(t);
        self.follow(raw);
        let mut angle = self.angle;
        if !torque_on {
            if let Some(a) = self.hand.as_ref().and_then(|h| h.angle_at(t)) {
                angle = a;
            }
        }
        angle = self.clamp_to_stops(angle);
        if let Some(c) = &self.contact {
            angle = c.admit(angle, before, dt, torque_on);
        }
        if angle == self.angle {
            return None;
        }
        self.angle = angle;
        self.raw = self.raw_of(angle);
        Some(self.raw)
    }

    /// Writes the truth samples of `(t0, t1]`, the angle having moved from `a0`.
    pub(crate) fn record(&self, t0: f64, t1: f64, a0: f64) {
        if let Some((truth, col)) = &self.truth {
            truth.record(*col, t0, t1, a0, self.angle);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use servobus_protocol::registers::STS3215;

    #[test]
    fn hand_eases_between_keyframes_and_lets_go_after_the_last() {
        let h = HandPath::new([(1.0, 0.0), (2.0, 90.0)]);
        assert_eq!(h.angle_at(0.5), None);
        assert_eq!(h.angle_at(1.0), Some(0.0));
        assert_eq!(h.angle_at(1.5), Some(45.0));
        assert!(
            h.angle_at(1.1).is_some_and(|a| a < 9.0 * 0.2),
            "eased start"
        );
        assert_eq!(h.angle_at(2.0), Some(90.0));
        assert_eq!(h.angle_at(2.01), None);
    }

    #[test]
    fn body_unwraps_the_seam() {
        // Zero at tick 4000, rising ticks positive: +20 deg is past the seam.
        let mut b = Body::new(Mount::new(4000.0, false), 0.0, &STS3215);
        let tpd = 4096.0 / 360.0;
        for k in 1..=200 {
            let a = 0.1 * f64::from(k);
            b.follow((4000.0 + a * tpd).rem_euclid(4096.0));
        }
        assert!((b.angle - 20.0).abs() < 1e-9, "{}", b.angle);
        assert!(b.raw_of(20.0) < 200.0);
    }

    #[test]
    fn truth_rows_wait_for_every_column() {
        let t = Truth::new(vec!["a".into(), "b".into()], Duration::from_millis(10));
        t.record(0, 0.0, 0.05, 0.0, 5.0);
        assert!(t.rows().is_empty());
        t.record(1, 0.0, 0.02, 1.0, 1.0);
        let rows = t.rows();
        assert_eq!(rows.len(), 3);
        assert!((rows[2].angles_deg[0] - 2.0).abs() < 1e-9);
        assert_eq!(t.take_rows().len(), 3);
        assert!(t.take_rows().is_empty());
        t.record(1, 0.02, 0.05, 1.0, 1.0);
        assert_eq!(t.take_rows().len(), 3);
    }
}
