//! Recorded paths: a dense recording (a hand-guided take, a logged run)
//! filtered into a path that respects every velocity, acceleration and
//! jerk limit without lagging behind the recording.
//!
//! Method, per joint:
//!
//! 1. **Forward tracker.** Every `step` seconds, the quickest jerk-limited
//!    move from the tracker's state to the recording's position then
//!    ([`retarget`](crate::retarget): time-optimal, ends at rest) is
//!    planned, and its first `step` is kept. The tracker follows the
//!    recording as closely as the limits allow, but a little late: it
//!    only reacts to what it has seen.
//! 2. **Backward tracker.** The same on the recording played backwards:
//!    in forward time it is early by about as much.
//! 3. **Average.** The path is the mean of the two. Velocity, acceleration
//!    and jerk limits are symmetric bounds, so the mean of two paths within
//!    them is within them too; the lateness of one and the earliness of the
//!    other cancel (exactly so for a steady ramp), so the result is not
//!    delayed. It starts at rest at the recording's first position and
//!    ends at rest at its last.
//!
//! Unlike a moving average, nothing here trades accuracy for smoothness:
//! where the recording is within the limits the trackers follow it, and
//! only steps and noise beyond them are rounded off.

use crate::error::{PlanError, Quantity};
use crate::limits::{check_keyframe, validate_all};
use crate::online::{finish, stop_phases};
use crate::piece::Piece;
use crate::profile::{Acc, Phases};
use crate::{retarget, JointLimits, JointState, Trajectory};

/// A recording filtered by [`track`], with how far it departs from the
/// recording.
#[derive(Debug, Clone)]
pub struct Tracked {
    /// The filtered path, from rest at the first sample to rest at the last.
    pub trajectory: Trajectory,
    /// Time in the path of the recording's first sample, s: the path may
    /// start moving a little earlier, to be on time for what follows.
    pub recording_start: f64,
    /// Per joint, the largest distance between the path and the recording
    /// (linearly interpolated) over the recording's time span.
    pub max_deviation: Vec<f64>,
    /// Per joint, the root mean square of that distance.
    pub rms_deviation: Vec<f64>,
}

/// Filters a recording (`times[i]` in s, increasing; `samples[i][j]` the
/// position of joint `j` then) into a path within `limits`, re-planned
/// every `step` s (the control period is a good choice).
///
/// # Errors
///
/// Invalid limits; fewer than two samples, times not increasing or not
/// finite, a sample of the wrong length ([`PlanError::WrongJointCount`]),
/// not finite or outside the position limits ([`PlanError::OutOfRange`],
/// with the sample's index as `keyframe`); a filtered path that would leave
/// the position limits (a recording pressed against a limit with a step
/// towards it) as [`PlanError::LimitExceeded`].
pub fn track(
    limits: &[JointLimits],
    times: &[f64],
    samples: &[Vec<f64>],
    step: f64,
) -> Result<Tracked, PlanError> {
    validate(limits, times, samples)?;
    let step = if step.is_finite() && step > 0.0 {
        step
    } else {
        0.005
    };
    let (t0, end) = (times[0], times[times.len() - 1] - times[0]);
    let mut per_joint = Vec::with_capacity(limits.len());
    let mut tail: f64 = 0.0;
    let mut lead = Vec::with_capacity(limits.len());
    for (j, lim) in limits.iter().enumerate() {
        let forward = |t: f64| reference(times, samples, j, t0 + t);
        let backward = |t: f64| reference(times, samples, j, t0 + end - t);
        let f = follow(lim, &forward, end, step)?;
        let b = follow(lim, &backward, end, step)?;
        // The backward path, in forward time, spans [end - b_len, end].
        let b_len = b.last().map_or(0.0, |p| p.t1);
        let f_len = f.last().map_or(0.0, |p| p.t1);
        let start = (end - b_len).min(0.0);
        let b_fwd: Vec<Piece> = b.iter().rev().map(|p| reversed(p, end)).collect();
        let mean = average(&f, &b_fwd, start, f_len.max(end));
        lead.push(-start);
        tail = tail.max(f_len.max(end));
        per_joint.push(mean);
    }
    // Every joint starts at the same instant: the earliest start.
    let shift = lead.iter().copied().fold(0.0, f64::max);
    let duration = shift + tail;
    for (j, (pieces, &l)) in per_joint.iter_mut().zip(&lead).enumerate() {
        let offset = shift - l;
        let mut shifted = Vec::with_capacity(pieces.len() + 2);
        if offset > 0.0 {
            shifted.push(Piece::hold(0.0, offset, samples[0][j]));
        }
        shifted.extend(pieces.iter().map(|p| Piece {
            t0: p.t0 + l + offset,
            t1: p.t1 + l + offset,
            c: p.c,
        }));
        *pieces = shifted;
    }
    // Every joint then rests at the recording's last position until the
    // slowest one is done.
    let trajectory = finish(per_joint, &samples[samples.len() - 1], duration);
    check_positions(limits, &trajectory)?;
    let (max_deviation, rms_deviation) = deviation(&trajectory, times, samples, shift, step);
    Ok(Tracked {
        trajectory,
        recording_start: shift,
        max_deviation,
        rms_deviation,
    })
}

fn validate(limits: &[JointLimits], times: &[f64], samples: &[Vec<f64>]) -> Result<(), PlanError> {
    validate_all(limits)?;
    if times.len() < 2 || samples.len() != times.len() {
        return Err(PlanError::NoKeyframes);
    }
    for (i, (&t, s)) in times.iter().zip(samples).enumerate() {
        if s.len() != limits.len() {
            return Err(PlanError::WrongJointCount {
                keyframe: i,
                expected: limits.len(),
                actual: s.len(),
            });
        }
        if !t.is_finite() {
            return Err(PlanError::NotFinite {
                keyframe: i,
                joint: 0,
            });
        }
        if i > 0 && t <= times[i - 1] {
            return Err(PlanError::TimeNotIncreasing {
                keyframe: i,
                at: t,
                previous: times[i - 1],
            });
        }
        check_keyframe(i, s, limits)?;
    }
    Ok(())
}

/// The recording of joint `j` at absolute time `t`, linearly interpolated
/// and held before the first and after the last sample.
fn reference(times: &[f64], samples: &[Vec<f64>], j: usize, t: f64) -> f64 {
    let i = times.partition_point(|&x| x <= t);
    if i == 0 {
        return samples[0][j];
    }
    if i >= times.len() {
        return samples[times.len() - 1][j];
    }
    let (ta, tb) = (times[i - 1], times[i]);
    let (a, b) = (samples[i - 1][j], samples[i][j]);
    a + (b - a) * (t - ta) / (tb - ta)
}

/// One tracker pass over `[0, end]` then on to rest at `r(end)`: pieces
/// from time 0, starting at rest at `r(0)`. Each step of `step` s has one
/// jerk (one acceleration without a jerk limit), the first of a short list
/// (full jerk towards the target, half, none, half and full away) that
/// keeps acceleration and speed within the limits and the quickest stop
/// from the new state short of the target: a time-optimal bang-bang
/// pursuit. When none does, the joint brakes along its quickest stop.
fn follow(
    lim: &JointLimits,
    r: &dyn Fn(f64) -> f64,
    end: f64,
    step: f64,
) -> Result<Vec<Piece>, PlanError> {
    let steps = (end / step).ceil() as usize;
    let mut out = Vec::with_capacity(steps + 16);
    let mut scratch = Vec::with_capacity(16);
    let mut x = JointState::at_rest(r(0.0));
    let mut t = 0.0;
    for k in 1..=steps {
        let target = r((k as f64 * step).min(end));
        let before = out.len();
        x = pursue(lim, x, target, t, step, &mut scratch, &mut out);
        debug_assert!(out.len() > before);
        t += step;
    }
    // On to rest at the last position, quickest jerk-limited way.
    let path = retarget(&[*lim], &[x], &[r(end)])?;
    for p in &path.pieces[0] {
        out.push(Piece {
            t0: t + p.t0,
            t1: t + p.t1,
            c: p.c,
        });
    }
    Ok(out)
}

/// Where the quickest stop from `x` ends.
fn stop_position(lim: &JointLimits, x: JointState, scratch: &mut Vec<Piece>) -> f64 {
    quickest_stop(lim, x, 0.0, scratch)
}

/// Replaces `scratch` with the pieces of the quickest stop from `x`, starting
/// at time `t`; returns where it ends.
fn quickest_stop(lim: &JointLimits, x: JointState, t: f64, scratch: &mut Vec<Piece>) -> f64 {
    let mut ph = Phases::new();
    stop_phases(x.velocity, x.acceleration, &Acc::of(lim), &mut ph);
    scratch.clear();
    ph.emit_from(t, &x, lim, scratch).1
}

/// One step of the pursuit from `x` at time `t`; appends its pieces and
/// returns the state at `t + dt`.
fn pursue(
    lim: &JointLimits,
    x: JointState,
    target: f64,
    t: f64,
    dt: f64,
    scratch: &mut Vec<Piece>,
    out: &mut Vec<Piece>,
) -> JointState {
    let (vm, am) = (lim.max_velocity, lim.max_acceleration);
    let tol = 1.0 + 1e-12;
    let gap = target - stop_position(lim, x, scratch);
    let s = if gap > 0.0 { 1.0 } else { -1.0 };
    for f in [1.0, 0.5, 0.0, -0.5, -1.0] {
        let piece = match lim.max_jerk {
            Some(jm) => {
                // Jerk, clamped so the acceleration ends within its limit.
                let u = (f * s * jm).clamp((-am - x.acceleration) / dt, (am - x.acceleration) / dt);
                Piece::jerk(t, dt, x.position, x.velocity, x.acceleration, u)
            }
            None => {
                // Acceleration, clamped so the speed ends within its limit.
                let a = (f * s * am).clamp((-vm - x.velocity) / dt, (vm - x.velocity) / dt);
                Piece::jerk(t, dt, x.position, x.velocity, a, 0.0)
            }
        };
        let (p, v, a) = piece.eval_local(dt);
        let next = JointState {
            position: p,
            velocity: v,
            acceleration: if lim.max_jerk.is_some() { a } else { 0.0 },
        };
        // Speed within the limit now and once the acceleration is ramped
        // to zero (it is monotone over the step, so the ends suffice).
        let ramp = lim.max_jerk.map_or(0.0, |jm| a * a.abs() / (2.0 * jm));
        let peak_a = piece.peak(2);
        if v.abs() > vm * tol || (v + ramp).abs() > vm * tol || peak_a > am * tol {
            continue;
        }
        if piece.peak(1) > vm * tol {
            continue;
        }
        let stop = stop_position(lim, next, scratch);
        if (target - stop) * s >= 0.0 || (f == 0.0 && gap.abs() < 1e-12) {
            out.push(piece);
            return next;
        }
    }
    // Brake along the quickest stop (first `dt` of it), then hold.
    quickest_stop(lim, x, t, scratch);
    let finite = lim.max_jerk.is_some();
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
        let (pp, vv, aa) = q.eval_local(q.duration());
        end = JointState {
            position: pp,
            velocity: vv,
            acceleration: if finite { aa } else { 0.0 },
        };
        covered = q.t1;
        out.push(q);
    }
    if covered < t + dt {
        out.push(Piece::hold(covered, t + dt, end.position));
        end = JointState::at_rest(end.position);
    }
    end
}

/// Piece `p` with time reversed about `t = end / 2`: `q(s) = p(end - s)`.
fn reversed(p: &Piece, end: f64) -> Piece {
    let len = p.duration();
    let (pos, vel, acc) = p.eval_local(len);
    let jerk = 6.0 * p.c[3];
    Piece {
        t0: end - p.t1,
        t1: end - p.t0,
        c: [pos, -vel, 0.5 * acc, -jerk / 6.0, 0.0, 0.0],
    }
}

/// The mean of two piecewise-cubic paths over `[from, to]`, each held at
/// its end state outside its pieces (at rest, by construction).
fn average(a: &[Piece], b: &[Piece], from: f64, to: f64) -> Vec<Piece> {
    let mut cuts: Vec<f64> = a
        .iter()
        .chain(b)
        .flat_map(|p| [p.t0, p.t1])
        .chain([from, to])
        .filter(|t| *t >= from && *t <= to)
        .collect();
    cuts.sort_by(f64::total_cmp);
    cuts.dedup_by(|x, y| (*x - *y).abs() < 1e-12);
    let (mut ia, mut ib) = (0, 0);
    let mut out = Vec::with_capacity(cuts.len());
    for w in cuts.windows(2) {
        let (u0, u1) = (w[0], w[1]);
        let mid = 0.5 * (u0 + u1);
        let ca = taylor(a, &mut ia, mid, u0);
        let cb = taylor(b, &mut ib, mid, u0);
        let mut c = [0.0; 6];
        for k in 0..4 {
            c[k] = 0.5 * (ca[k] + cb[k]);
        }
        out.push(Piece { t0: u0, t1: u1, c });
    }
    out
}

/// Cubic coefficients, about `at`, of the piece of `ps` holding `mid`
/// (`i`: a cursor moving forward); outside the pieces, the held end.
fn taylor(ps: &[Piece], i: &mut usize, mid: f64, at: f64) -> [f64; 4] {
    while *i + 1 < ps.len() && ps[*i].t1 < mid {
        *i += 1;
    }
    let Some(p) = ps.get(*i) else {
        return [0.0; 4];
    };
    if mid < p.t0 {
        return [p.eval_local(0.0).0, 0.0, 0.0, 0.0];
    }
    if mid > p.t1 {
        return [p.eval_local(p.duration()).0, 0.0, 0.0, 0.0];
    }
    let (pos, vel, acc) = p.eval_local(at - p.t0);
    [pos, vel, 0.5 * acc, p.c[3]]
}

fn check_positions(limits: &[JointLimits], t: &Trajectory) -> Result<(), PlanError> {
    for (j, l) in limits.iter().enumerate() {
        let Some(s) = t.joint_summary(j) else {
            continue;
        };
        let slack = 1e-9 * (1.0 + l.max_position.abs().max(l.min_position.abs()).min(1e12));
        let below =
            (s.min_position < l.min_position - slack).then_some((s.min_position, l.min_position));
        let above =
            (s.max_position > l.max_position + slack).then_some((s.max_position, l.max_position));
        if let Some((peak, limit)) = below.or(above) {
            return Err(PlanError::LimitExceeded {
                keyframe: 0,
                joint: j,
                quantity: Quantity::Position,
                peak,
                limit,
            });
        }
    }
    Ok(())
}

/// Max and RMS distance between the path (shifted by `shift`) and the
/// recording, sampled every `step` over the recording.
fn deviation(
    t: &Trajectory,
    times: &[f64],
    samples: &[Vec<f64>],
    shift: f64,
    step: f64,
) -> (Vec<f64>, Vec<f64>) {
    let n = t.joints();
    let (mut max, mut sum) = (vec![0.0f64; n], vec![0.0; n]);
    let mut out = vec![JointState::default(); n];
    let mut cursor = t.cursor();
    let span = times[times.len() - 1] - times[0];
    let count = (span / step).ceil() as usize + 1;
    for k in 0..count {
        let x = (k as f64 * step).min(span);
        t.sample_with(&mut cursor, shift + x, &mut out);
        for j in 0..n {
            let e = out[j].position - reference(times, samples, j, times[0] + x);
            max[j] = max[j].max(e.abs());
            sum[j] += e * e;
        }
    }
    let rms = sum.iter().map(|s| (s / count as f64).sqrt()).collect();
    (max, rms)
}
