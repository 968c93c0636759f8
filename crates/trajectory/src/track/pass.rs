//! One tracking pass over a reference path (the recording's spline,
//! forwards or backwards in time), one control step at a time.
//!
//! - **On the reference**: where the reference's pieces over a step keep
//!   within every limit and end in a state from which the joint can still
//!   keep within them, they are copied: the pass *is* the reference there,
//!   to the last bit, with no delay.
//! - **Off it**: where they do not, the pass follows the reference's own
//!   jerk clamped to the limits while it is close, pursues its position
//!   (time-optimal bang-bang, one jerk per step) while it is far, and,
//!   every step, tries to rejoin it exactly with a quintic blend of a few
//!   steps whose sum with the reference keeps within the limits.
//!
//! The stretches off the reference are kept: they are where the recording
//! breaks a limit, and the report says so.

use crate::online::stop_phases;
use crate::piece::Piece;
use crate::profile::{Acc, Phases};
use crate::{retarget, JointLimits, JointState, PlanError};

/// Relative slack on every limit: rounding only.
const SLACK: f64 = 1e-9;

/// Lengths, in steps, of the blends tried to rejoin the reference, shortest
/// first. The longest (0.16 s at 200 Hz) is enough for an error the
/// pursuit leaves; a longer blend would rather wait for a stretch where the
/// reference leaves room.
const BLENDS: [usize; 10] = [1, 2, 3, 4, 6, 8, 12, 16, 24, LONGEST];

/// How far beyond its speed and acceleration limits a reference may be
/// for its own jerk to be followed when off it: a rounding or a
/// slightly too brisk take is within; a step or noise is many times over.
const CALM: f64 = 2.0;

/// The longest blend, in steps.
const LONGEST: usize = 32;

/// One joint's reference: pieces from 0 to `end`, each starting where the
/// last ends, at rest at both ends.
pub(super) struct Reference<'a> {
    pieces: &'a [Piece],
    end: f64,
}

impl<'a> Reference<'a> {
    /// The reference of `pieces` (not empty, contiguous) over `[0, end]`.
    pub fn new(pieces: &'a [Piece], end: f64) -> Self {
        Reference { pieces, end }
    }

    /// The piece holding `t` (the later one at a knot).
    fn index(&self, t: f64) -> usize {
        self.pieces
            .partition_point(|p| p.t1 <= t)
            .min(self.pieces.len() - 1)
    }

    /// The reference's state at `t`.
    pub fn state(&self, t: f64) -> JointState {
        let (position, velocity, acceleration) = self.pieces[self.index(t)].eval(t);
        JointState {
            position,
            velocity,
            acceleration,
        }
    }

    /// The reference over `[a, b]`, cut to it, in `out` (cleared first).
    fn window(&self, a: f64, b: f64, out: &mut Vec<Piece>) {
        out.clear();
        for p in &self.pieces[self.index(a)..] {
            let (u0, u1) = (a.max(p.t0), b.min(p.t1));
            if u1 > u0 {
                out.push(p.part(u0, u1));
            }
            if p.t1 >= b {
                break;
            }
        }
        match out.last_mut() {
            // Rounding of the knots may leave the last piece short of `b`.
            Some(last) => last.t1 = last.t1.max(b),
            None => out.push(self.pieces[self.index(a)].part(a, b)),
        }
    }
}

/// A pass: its pieces from time 0, and the stretches `[leave, back]` it
/// spent off the reference.
pub(super) struct Pass {
    pub pieces: Vec<Piece>,
    pub off: Vec<(f64, f64)>,
}

/// The limits of a pass: the joint's, and those as the recording can show
/// them (the joint's, widened by what the rounding of the recording's
/// numbers makes of its differences). The reference is followed where it
/// keeps within the second; the pass's own pursuit keeps within the first.
#[derive(Debug, Clone, Copy)]
pub(super) struct Limits {
    pub strict: JointLimits,
    pub shown: JointLimits,
}

/// Tracks `r` within `lims`, a step of `step` s at a time, from rest at
/// `first`, then on to rest at `last`.
///
/// # Errors
/// Only the final move to rest, which should not fail ([`retarget`]).
pub(super) fn run(
    lims: &Limits,
    r: &Reference,
    step: f64,
    (first, last): (f64, f64),
) -> Result<Pass, PlanError> {
    let (lim, shown) = (&lims.strict, &lims.shown);
    let end = r.end;
    let steps = step_count(end, step);
    // The last step ends at `end` exactly, whatever the rounding of
    // `steps * step`.
    let time = |k: usize| {
        if k >= steps {
            end
        } else {
            (k as f64 * step).min(end)
        }
    };
    let mut out = Vec::with_capacity(steps + 16);
    let mut off = Vec::new();
    let (mut win, mut scratch) = (Vec::with_capacity(64), Vec::with_capacity(16));
    let mut x = JointState::at_rest(first);
    let mut on = same(lim, &x, &r.state(0.0));
    let mut left = 0.0;
    let mut k = 0;
    while k < steps {
        let (t, t1) = (time(k), time(k + 1));
        if on {
            r.window(t, t1, &mut win);
            if fits(shown, &win, &mut scratch) {
                x = end_state(&win[win.len() - 1]);
                out.extend_from_slice(&win);
                k += 1;
                continue;
            }
            on = false;
            left = t;
        } else if let Some(k1) = rejoin(shown, r, x, k, steps, &time, &mut win, &mut scratch) {
            x = end_state(&win[win.len() - 1]);
            out.extend_from_slice(&win);
            off.push((left, time(k1)));
            on = true;
            k = k1;
            continue;
        }
        let (r0, r1) = (r.state(t), r.state(t1));
        // Its own jerk is worth following where its speed and acceleration
        // mean something: near the limits (a step or noise is far beyond).
        let calm = |r: &JointState| {
            r.velocity.abs() <= CALM * shown.max_velocity
                && r.acceleration.abs() <= CALM * shown.max_acceleration
        };
        let close = calm(&r0) && calm(&r1) && closes(lim, &relative(&x, &r0), t1 - t);
        x = pursue(lim, x, (r0, r1), close, t, t1 - t, &mut scratch, &mut out);
        k += 1;
    }
    if !(on && same(lim, &x, &JointState::at_rest(last))) {
        if on {
            left = end;
        }
        // Off the reference, or the reference not at rest at the last
        // sample: on to rest there, the quickest jerk-limited way.
        let path = retarget(&[relaxed(lim, &x)], &[x], &[last])?;
        out.extend(path.pieces[0].iter().map(|p| Piece {
            t0: end + p.t0,
            t1: end + p.t1,
            c: p.c,
        }));
        off.push((left, end + path.duration()));
    }
    Ok(Pass { pieces: out, off })
}

/// Steps needed to cover `[0, end]` in steps of `step`, each of positive
/// length: a remainder below [`STEP_ROUNDING`] of a step (the rounding of
/// `end / step`, as in `0.28 / 0.005 = 56.00000000000001`) lengthens the
/// last step instead of making one of (about) zero length, over which
/// every rate of the pursuit would divide by zero.
fn step_count(end: f64, step: f64) -> usize {
    (end / step - STEP_ROUNDING).ceil().max(1.0) as usize
}

/// The fraction of a step below which a remainder of the recording is
/// rounding, not a step of its own.
const STEP_ROUNDING: f64 = 1e-6;

/// Whether two states are the same but for rounding (their accelerations
/// too when `lim` limits the jerk; without a jerk limit they may jump).
fn same(lim: &JointLimits, x: &JointState, y: &JointState) -> bool {
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * (1.0 + a.abs().max(b.abs()));
    close(x.position, y.position)
        && close(x.velocity, y.velocity)
        && (lim.max_jerk.is_none() || close(x.acceleration, y.acceleration))
}

/// The state at the end of piece `p`.
fn end_state(p: &Piece) -> JointState {
    let (position, velocity, acceleration) = p.eval_local(p.duration());
    JointState {
        position,
        velocity,
        acceleration,
    }
}

/// Whether `lo..=hi` is within the position limits (with rounding slack).
fn within_positions(lim: &JointLimits, lo: f64, hi: f64) -> bool {
    let size = lim.max_position.abs().max(lim.min_position.abs()).min(1e12);
    let slack = SLACK * (1.0 + size);
    lo >= lim.min_position - slack && hi <= lim.max_position + slack
}

/// Whether `pieces` keep within every limit and end in a state from which
/// the joint can still keep within them ([`safe`]).
fn fits(lim: &JointLimits, pieces: &[Piece], scratch: &mut Vec<Piece>) -> bool {
    let tol = 1.0 + SLACK;
    for p in pieces {
        if p.peak(1) > lim.max_velocity * tol || p.peak(2) > lim.max_acceleration * tol {
            return false;
        }
        if lim.max_jerk.is_some_and(|jm| p.peak(3) > jm * tol) {
            return false;
        }
        let (lo, hi) = p.range(0);
        if !within_positions(lim, lo, hi) {
            return false;
        }
    }
    pieces
        .last()
        .is_none_or(|p| safe(lim, end_state(p), scratch))
}

/// Whether a joint in state `x` can keep within its limits from here on:
/// speed and acceleration within them, the speed still once the
/// acceleration is ramped to zero, and the quickest stop inside the
/// position limits. From such a state braking always keeps so.
fn safe(lim: &JointLimits, x: JointState, scratch: &mut Vec<Piece>) -> bool {
    let tol = 1.0 + SLACK;
    let vm = lim.max_velocity * tol;
    if x.velocity.abs() > vm {
        return false;
    }
    if let Some(jm) = lim.max_jerk {
        let a = x.acceleration;
        if a.abs() > lim.max_acceleration * tol
            || (x.velocity + a * a.abs() / (2.0 * jm)).abs() > vm
        {
            return false;
        }
    }
    let stop = quickest_stop(lim, x, 0.0, scratch);
    within_positions(lim, stop, stop)
}

/// Replaces `scratch` with the pieces of the quickest stop from `x`,
/// starting at time `t`; returns where it ends.
fn quickest_stop(lim: &JointLimits, x: JointState, t: f64, scratch: &mut Vec<Piece>) -> f64 {
    let mut ph = Phases::new();
    stop_phases(x.velocity, x.acceleration, &Acc::of(lim), &mut ph);
    scratch.clear();
    ph.emit_from(t, &x, lim, scratch).1
}

/// `lim` with the speed and acceleration limits raised to those of `x`
/// where it is beyond them.
fn relaxed(lim: &JointLimits, x: &JointState) -> JointLimits {
    JointLimits {
        max_velocity: lim.max_velocity.max(x.velocity.abs()),
        max_acceleration: lim.max_acceleration.max(x.acceleration.abs()),
        ..*lim
    }
}

/// `x - r`: a state in the frame of the reference.
fn relative(x: &JointState, r: &JointState) -> JointState {
    JointState {
        position: x.position - r.position,
        velocity: x.velocity - r.velocity,
        acceleration: x.acceleration - r.acceleration,
    }
}

/// The quintic from `e` (position, velocity, acceleration) at 0 to rest at
/// zero at `h`: the blend that, added to the reference, takes the joint
/// from where it is back onto it.
pub(super) fn blend(e: &JointState, h: f64) -> [f64; 6] {
    let (p, v, a) = (e.position, e.velocity, e.acceleration);
    let (h2, h3) = (h * h, h * h * h);
    [
        p,
        v,
        0.5 * a,
        -(20.0 * p + 12.0 * v * h + 3.0 * a * h2) / (2.0 * h3),
        (30.0 * p + 16.0 * v * h + 3.0 * a * h2) / (2.0 * h3 * h),
        -(12.0 * p + 6.0 * v * h + a * h2) / (2.0 * h3 * h2),
    ]
}

/// Whether blend `c` over `h` may fit: its jerk at both ends (or, without
/// a jerk limit, its acceleration half way) within twice the limit, since
/// the reference's own is within the limit at best. Spares the exact check
/// of most blends that cannot fit.
fn plausible(lim: &JointLimits, c: &[f64; 6], h: f64) -> bool {
    match lim.max_jerk {
        Some(jm) => {
            let j0 = 6.0 * c[3];
            let j1 = j0 + 24.0 * c[4] * h + 60.0 * c[5] * h * h;
            j0.abs().max(j1.abs()) <= 2.0 * jm
        }
        None => {
            let x = 0.5 * h;
            let a = 2.0 * c[2] + x * (6.0 * c[3] + x * (12.0 * c[4] + x * 20.0 * c[5]));
            a.abs() <= 2.0 * lim.max_acceleration
        }
    }
}

/// The bandwidth of the correction close to the reference, 1/s: twice
/// the inverse of the time the acceleration takes to ramp to its limit
/// (about the quickest the joint answers anyway), and slow enough for the
/// step. A critically damped correction at that pace follows the
/// reference's own jerk back onto it without ringing.
fn bandwidth(lim: &JointLimits, dt: f64) -> f64 {
    let by_limits = match lim.max_jerk {
        Some(jm) => 2.0 * jm / lim.max_acceleration,
        None => 2.0 * lim.max_acceleration / lim.max_velocity,
    };
    by_limits.min(0.2 / dt)
}

/// Whether an error `e` from the reference is small enough for the
/// correction: its jerk (acceleration) within the limit.
fn closes(lim: &JointLimits, e: &JointState, dt: f64) -> bool {
    let w = bandwidth(lim, dt);
    match lim.max_jerk {
        Some(jm) => {
            (w * (3.0 * e.acceleration + w * (3.0 * e.velocity + w * e.position))).abs() <= jm
        }
        None => (w * (2.0 * e.velocity + w * e.position)).abs() <= lim.max_acceleration,
    }
}

/// Tries to rejoin the reference from `x` at step `k` with the shortest
/// blend of [`BLENDS`] that keeps within the limits: its pieces in `win`
/// and the step it ends at.
#[allow(clippy::too_many_arguments)] // a pass's state and its buffers
fn rejoin(
    lim: &JointLimits,
    r: &Reference,
    x: JointState,
    k: usize,
    steps: usize,
    time: &dyn Fn(usize) -> f64,
    win: &mut Vec<Piece>,
    scratch: &mut Vec<Piece>,
) -> Option<usize> {
    let t = time(k);
    let e = relative(&x, &r.state(t));
    for m in BLENDS {
        let k1 = (k + m).min(steps);
        let t1 = time(k1);
        let c = blend(&e, t1 - t);
        if plausible(lim, &c, t1 - t) {
            r.window(t, t1, win);
            let correction = Piece { t0: t, t1, c };
            for p in win.iter_mut() {
                let d = correction.about(p.t0);
                for (pc, dc) in p.c.iter_mut().zip(d) {
                    *pc += dc;
                }
            }
            if fits(lim, win, scratch) {
                return Some(k1);
            }
        }
        if k1 == steps {
            break;
        }
    }
    None
}

/// One step off the reference, from `x` at `t` for `dt`, the reference
/// going from `r.0` to `r.1`: appends its pieces and returns the state
/// reached.
///
/// Close to the reference (`close`: an error a blend could take back), the
/// step follows the reference's own jerk (its acceleration, without a jerk
/// limit) clamped to the limits, so the error grows no more than the
/// reference's excess makes it, until a blend takes it back. Further off,
/// or where that does not keep within the limits, one jerk that pursues
/// the reference's position at the end of the step: the first of a short
/// list (full jerk toward it, half, none, half and full away) that keeps
/// within the limits and the quickest stop short of the target, a
/// time-optimal bang-bang pursuit. When none does, the quickest stop.
#[allow(clippy::too_many_arguments)] // a step's state, the reference's and the buffers
fn pursue(
    lim: &JointLimits,
    x: JointState,
    (r0, r1): (JointState, JointState),
    close: bool,
    t: f64,
    dt: f64,
    scratch: &mut Vec<Piece>,
    out: &mut Vec<Piece>,
) -> JointState {
    debug_assert!(dt > 0.0, "a step of positive length ({dt} s)");
    let (vm, am) = (lim.max_velocity, lim.max_acceleration);
    // Just off the reference, the joint may be beyond the strict limits by
    // what the recording's rounding allows: from there it may not go
    // further beyond them.
    let bounds = relaxed(lim, &x);
    let step = |u: f64| match lim.max_jerk {
        // Jerk, clamped so the acceleration ends within its limit.
        Some(jm) => {
            let u = u
                .clamp(-jm, jm)
                .clamp((-am - x.acceleration) / dt, (am - x.acceleration) / dt);
            Piece::jerk(t, dt, x.position, x.velocity, x.acceleration, u)
        }
        // Acceleration, clamped so the speed ends within its limit.
        None => {
            let a = u
                .clamp(-am, am)
                .clamp((-vm - x.velocity) / dt, (vm - x.velocity) / dt);
            Piece::jerk(t, dt, x.position, x.velocity, a, 0.0)
        }
    };
    if close {
        let e = relative(&x, &r0);
        let w = bandwidth(lim, dt);
        let u = match lim.max_jerk {
            Some(_) => {
                let own = (r1.acceleration - r0.acceleration) / dt;
                own - w * (3.0 * e.acceleration + w * (3.0 * e.velocity + w * e.position))
            }
            None => {
                let own = (r1.velocity - r0.velocity) / dt;
                own - w * (2.0 * e.velocity + w * e.position)
            }
        };
        let piece = step(u);
        if fits(&bounds, core::slice::from_ref(&piece), scratch) {
            out.push(piece);
            return end_state(&piece);
        }
    }
    let target = r1.position;
    let gap = target - quickest_stop(lim, x, 0.0, scratch);
    let s = if gap > 0.0 { 1.0 } else { -1.0 };
    let full = lim.max_jerk.unwrap_or(am);
    for f in [1.0, 0.5, 0.0, -0.5, -1.0] {
        let piece = step(f * s * full);
        if !fits(&bounds, core::slice::from_ref(&piece), scratch) {
            continue;
        }
        let next = end_state(&piece);
        let stop = quickest_stop(lim, next, 0.0, scratch);
        if (target - stop) * s >= 0.0 || (f == 0.0 && gap.abs() < 1e-12) {
            out.push(piece);
            return next;
        }
    }
    brake(lim, x, t, dt, scratch, out)
}

/// The first `dt` of the quickest stop from `x` at `t` (then rest): the
/// step that always keeps within the limits from a [`safe`] state.
fn brake(
    lim: &JointLimits,
    x: JointState,
    t: f64,
    dt: f64,
    scratch: &mut Vec<Piece>,
    out: &mut Vec<Piece>,
) -> JointState {
    quickest_stop(lim, x, t, scratch);
    let mut end = JointState::at_rest(x.position);
    let mut covered = t;
    for p in scratch.iter() {
        if p.t0 >= t + dt {
            break;
        }
        let q = Piece {
            t0: p.t0,
            t1: p.t1.min(t + dt),
            c: p.c,
        };
        end = end_state(&q);
        if lim.max_jerk.is_none() {
            end.acceleration = 0.0;
        }
        covered = q.t1;
        out.push(q);
    }
    if covered < t + dt {
        out.push(Piece::hold(covered, t + dt, end.position));
        end = JointState::at_rest(end.position);
    }
    end
}
