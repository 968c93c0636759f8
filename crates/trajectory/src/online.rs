//! Online changes from an arbitrary current state: retarget and stop.
//!
//! Both start at time 0 in the given state (sample the running trajectory
//! at "now" to get it) and end at rest.

use crate::error::PlanError;
use crate::limits::validate_all;
use crate::piece::Piece;
use crate::profile::{Acc, Phases, Ramp, Segment1, SIXTH};
use crate::{JointLimits, JointState, Trajectory};

/// The quickest way to rest from speed `v` and acceleration `a`: ramp the
/// acceleration to a deceleration peak (at most `max_acceleration`), hold
/// it, ramp it back to zero exactly as the speed reaches zero. This
/// bang-bang jerk profile is the time-optimal one for reaching zero speed
/// and zero acceleration.
pub(crate) fn stop_phases(v: f64, a: f64, lim: &Acc, out: &mut Phases) {
    let (am, j, inv_j, finite) = (lim.a, lim.j, lim.inv_j, lim.finite);
    // Speed reached if the acceleration were ramped to zero right away.
    let v_flat = if finite {
        v + a * a.abs() * (0.5 * inv_j)
    } else {
        v
    };
    if v_flat == 0.0 {
        if finite && a != 0.0 {
            out.push(a.abs() * inv_j, -a.signum() * j, 0.0);
        }
        return;
    }
    // Normalise so that the speed must decrease.
    let dir = v_flat.signum();
    let (mut v, mut a) = (dir * v, if finite { dir * a } else { 0.0 });
    if a < -am {
        // Decelerating harder than allowed (a state from outside the
        // limits): first bring the deceleration back to the limit.
        let dt = (-am - a) * inv_j;
        out.push(dt, dir * j, 0.0);
        v += dt * (a + 0.5 * dt * j);
        a = -am;
    }
    let excess = if finite { v + a * a * (0.5 * inv_j) } else { v };
    let (ap, hold) = if finite && excess <= lim.regime {
        ((j * excess).sqrt(), 0.0)
    } else {
        // `regime` is 0 without a jerk limit: the hold is `excess / am`.
        (am, (excess - lim.regime) * lim.inv_a)
    };
    if finite {
        out.push((a + ap) * inv_j, -dir * j, 0.0);
    }
    out.push(hold, 0.0, -dir * ap);
    if finite {
        out.push(ap * inv_j, dir * j, 0.0);
    }
}

fn check_states(limits: &[JointLimits], states: &[JointState]) -> Result<(), PlanError> {
    validate_all(limits)?;
    if states.len() != limits.len() {
        return Err(PlanError::WrongJointCount {
            keyframe: 0,
            expected: limits.len(),
            actual: states.len(),
        });
    }
    for (j, s) in states.iter().enumerate() {
        if !(s.position.is_finite() && s.velocity.is_finite() && s.acceleration.is_finite()) {
            return Err(PlanError::NotFinite {
                keyframe: 0,
                joint: j,
            });
        }
    }
    Ok(())
}

/// Brings every joint to rest as fast as its limits allow, from any state
/// (for cancel and faults). Each joint stops in its own minimal time; the
/// trajectory lasts as long as the slowest. Positions are not limited: a
/// joint that cannot stop before a position limit passes it.
///
/// # Errors
///
/// Invalid limits, a state count that does not match, or a state that is
/// not finite.
pub fn stop(limits: &[JointLimits], current: &[JointState]) -> Result<Trajectory, PlanError> {
    check_states(limits, current)?;
    let mut per_joint: Vec<Vec<Piece>> = Vec::with_capacity(limits.len());
    let mut hold = Vec::with_capacity(limits.len());
    let mut duration: f64 = 0.0;
    for (lim, s) in limits.iter().zip(current) {
        let mut ph = Phases::new();
        stop_phases(s.velocity, s.acceleration, &Acc::of(lim), &mut ph);
        let mut pieces = Vec::with_capacity(ph.n + 1);
        let (t, p, _, _) = ph.emit_from(0.0, s, lim, &mut pieces);
        duration = duration.max(t);
        hold.push(p);
        per_joint.push(pieces);
    }
    Ok(finish(per_joint, &hold, duration))
}

/// The trajectory of `per_joint`, every joint padded with a rest piece at
/// `hold[j]` up to `duration`.
pub(crate) fn finish(mut per_joint: Vec<Vec<Piece>>, hold: &[f64], duration: f64) -> Trajectory {
    for (ps, &p) in per_joint.iter_mut().zip(hold) {
        let end = ps.last().map_or(0.0, |l| l.t1);
        if end < duration {
            ps.push(Piece::hold(end, duration, p));
        }
    }
    Trajectory::from_joints(per_joint, hold, duration, Vec::new())
}

/// How one joint starts toward its target, the phases before the main
/// segment aside (those are written where the caller keeps them).
pub(crate) struct Route1 {
    /// Duration of the phases before the main segment.
    pub pre_time: f64,
    pub seg: Segment1,
    /// Direction of the main segment.
    pub dir: f64,
}

/// Whether a joint at speed `v >= 0` (within `max_velocity`), with no
/// acceleration, can still come to rest within `dist`: the rest-to-rest
/// move peaking at `v` covers `v` times its ramp's duration, which grows
/// with `v`, so this is `v <= rest_peak(dist)` without solving for the
/// peak (no cube root).
#[inline]
fn rests_within(v: f64, dist: f64, lim: &Acc) -> bool {
    v * Ramp::of(v, lim).duration() <= dist
}

/// The segment of `d` (either sign) from speed `v0` (in its direction) to
/// rest.
fn onto(d: f64, v0: f64) -> (Segment1, f64) {
    let seg = Segment1 {
        d: d.abs(),
        v0: v0.abs(),
        v1: 0.0,
    };
    (seg, if d >= 0.0 { 1.0 } else { -1.0 })
}

/// How one joint goes on toward `target` without reversing: its
/// acceleration ramped to zero (the phase written to `pre`, cleared
/// first), then the main segment. `None` when that will not do: the
/// speed points away from the target, or is too high to stop within a
/// quarter of the distance.
pub(crate) fn onward(s: &JointState, target: f64, lim: &Acc, pre: &mut Phases) -> Option<Route1> {
    let (j, finite) = (lim.j, lim.finite);
    pre.n = 0;
    let (ta, a) = if finite {
        (s.acceleration.abs() * lim.inv_j, s.acceleration)
    } else {
        (0.0, 0.0)
    };
    let jj = -a.signum() * j;
    let (p1, v1) = if finite {
        (
            s.position + ta * (s.velocity + ta * (0.5 * a + ta * jj * SIXTH)),
            s.velocity + ta * (a + 0.5 * ta * jj),
        )
    } else {
        (s.position, s.velocity)
    };
    let d = target - p1;
    let on = v1 == 0.0
        || (v1 * d > 0.0 && v1.abs() <= lim.vm && rests_within(v1.abs(), 0.5 * d.abs(), lim));
    if !on {
        return None;
    }
    if finite && a != 0.0 {
        pre.push(ta, jj, 0.0);
    }
    let (seg, dir) = onto(d, v1);
    Some(Route1 {
        pre_time: ta,
        seg,
        dir,
    })
}

/// How one joint gets from its state to `target`: [`onward`] when it can,
/// else it stops as fast as it can and then moves rest to rest. The phases
/// before the main segment are written to `pre`.
pub(crate) fn route(s: &JointState, target: f64, lim: &Acc, pre: &mut Phases) -> Route1 {
    if let Some(way) = onward(s, target, lim, pre) {
        return way;
    }
    pre.n = 0;
    stop_phases(s.velocity, s.acceleration, lim, pre);
    let (t, p, _, _) = pre.advance(s, 1.0, lim.finite, f64::INFINITY);
    let (seg, dir) = onto(target - p, 0.0);
    Route1 {
        pre_time: t,
        seg,
        dir,
    }
}

/// Moves every joint from its current state to `target` (at rest), jerk
/// limited, all joints arriving together, starting at time 0.
///
/// Each joint either ramps its acceleration to zero and continues to the
/// target (when it is already heading there slowly enough to stop in
/// time), or stops as fast as it can and then moves rest to rest. The
/// slowest joint sets the duration; the others' final segments are
/// stretched to match. Velocity and acceleration are continuous from the
/// given state on. If the state is beyond a limit (say faster than
/// `max_velocity`) the path returns inside the limits as fast as they
/// allow.
///
/// # Errors
///
/// Invalid limits, counts that do not match, values that are not finite,
/// or a target outside the position limits ([`PlanError::OutOfRange`],
/// keyframe 0).
pub fn retarget(
    limits: &[JointLimits],
    current: &[JointState],
    target: &[f64],
) -> Result<Trajectory, PlanError> {
    check_states(limits, current)?;
    if target.len() != limits.len() {
        return Err(PlanError::WrongJointCount {
            keyframe: 0,
            expected: limits.len(),
            actual: target.len(),
        });
    }
    for (j, (&q, l)) in target.iter().zip(limits).enumerate() {
        if !q.is_finite() {
            return Err(PlanError::NotFinite {
                keyframe: 0,
                joint: j,
            });
        }
        if q < l.min_position || q > l.max_position {
            return Err(PlanError::OutOfRange {
                keyframe: 0,
                joint: j,
                position: q,
                min: l.min_position,
                max: l.max_position,
            });
        }
    }
    // Each joint's route first (the slowest sets the duration), then its
    // main segment stretched to it; a joint's pieces are allocated once
    // all its phases are known, no more than it uses (one spare for the
    // rest at the end), so that none is allocated twice.
    let mut ways = Vec::with_capacity(limits.len());
    let mut duration: f64 = 0.0;
    for ((s, &q), lim) in current.iter().zip(target).zip(limits) {
        let mut pre = Phases::new();
        let acc = Acc::of(lim);
        let way = route(s, q, &acc, &mut pre);
        let fastest = way.seg.fastest(&acc);
        duration = duration.max(way.pre_time + fastest.duration);
        ways.push((way, fastest, pre, acc));
    }
    let mut per_joint = Vec::with_capacity(limits.len());
    let mut main = Phases::new();
    for ((s, (way, fastest, pre, acc)), lim) in current.iter().zip(ways).zip(limits) {
        main.n = 0;
        if way.seg.d > 0.0 || way.seg.v0 > 0.0 {
            let prof = way.seg.stretched(&acc, fastest, duration - way.pre_time);
            way.seg.phases(&acc, prof, &mut main);
        }
        let mut pieces = Vec::with_capacity(pre.n + main.n + 1);
        let (t, x, v, _) = pre.emit_from(0.0, s, lim, &mut pieces);
        main.emit(t, x, v, 0.0, way.dir, lim.max_jerk.is_some(), &mut pieces);
        per_joint.push(pieces);
    }
    Ok(finish(per_joint, target, duration))
}
