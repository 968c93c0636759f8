//! Keyframes in, trajectory out: splits the keyframe list into timed and
//! untimed sections and joins them at rest.

use crate::error::{PlanError, Quantity};
use crate::limits::{check_keyframe, validate_all};
use crate::piece::Piece;
use crate::spline::{self, TimedShape};
use crate::timed;
use crate::trajectory::SegmentTiming;
use crate::untimed::{self, Scratch};
use crate::{JointLimits, Trajectory};

/// A pose to pass through: one position per joint, optionally at a time.
#[derive(Debug, Clone, PartialEq)]
pub struct Keyframe {
    /// One position per joint, in the limits' order and unit.
    pub positions: Vec<f64>,
    /// Time (s, from the start of the cycle) at which to be exactly here;
    /// `None`: as soon as the limits allow.
    pub at: Option<f64>,
    /// Interpolation of the timed segment arriving here; `None`: the
    /// plan's [`PlanOptions::shape`]. Ignored for untimed keyframes.
    pub shape: Option<TimedShape>,
}

impl Keyframe {
    /// An untimed keyframe.
    pub fn new(positions: impl Into<Vec<f64>>) -> Self {
        Keyframe {
            positions: positions.into(),
            at: None,
            shape: None,
        }
    }

    /// The same keyframe, reached at `at` seconds.
    pub fn at(mut self, at: f64) -> Self {
        self.at = Some(at);
        self
    }

    /// The same keyframe, with the segment arriving here shaped `shape`.
    pub fn shape(mut self, shape: TimedShape) -> Self {
        self.shape = Some(shape);
        self
    }
}

/// What to do when a timed segment would exceed a limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum OnLimit {
    /// Refuse with [`PlanError::LimitExceeded`] or [`PlanError::TooSoon`].
    #[default]
    Error,
    /// Stretch the timing of the offending segments (and delay every later
    /// keyframe by as much) until the limits hold.
    Stretch,
}

/// Options of [`plan`].
#[derive(Debug, Clone, PartialEq)]
pub struct PlanOptions {
    /// Default interpolation of timed segments.
    pub shape: TimedShape,
    /// Timed segments beyond a limit: error or stretch.
    pub on_limit: OnLimit,
    /// How many times the keyframe list is played (>= 1). Between cycles the
    /// last keyframe moves on to the first one (untimed) unless they are
    /// equal; a cycle's times count from its first keyframe's arrival.
    pub repeat: u32,
    /// Stop at every untimed keyframe instead of passing through (the
    /// slower, simpler motion; mostly useful for comparison).
    pub stop_at_keyframes: bool,
}

impl Default for PlanOptions {
    fn default() -> Self {
        PlanOptions {
            shape: TimedShape::ShapePreserving,
            on_limit: OnLimit::Error,
            repeat: 1,
            stop_at_keyframes: false,
        }
    }
}

/// A keyframe of the expanded (repeated) list.
struct Entry<'a> {
    pos: &'a [f64],
    at: Option<f64>,
    shape: TimedShape,
    index: usize,
    cycle: usize,
    /// This entry's arrival is the time origin of the following `at`s.
    rebase: bool,
    /// Untimed motion must stop here (a cycle start followed by timed
    /// keyframes: their times depend on this arrival).
    boundary: bool,
}

fn validate(
    limits: &[JointLimits],
    keyframes: &[Keyframe],
    options: &PlanOptions,
) -> Result<(), PlanError> {
    validate_all(limits)?;
    if keyframes.is_empty() {
        return Err(PlanError::NoKeyframes);
    }
    if options.repeat == 0 {
        return Err(PlanError::ZeroRepeat);
    }
    for (k, kf) in keyframes.iter().enumerate() {
        if kf.positions.len() != limits.len() {
            return Err(PlanError::WrongJointCount {
                keyframe: k,
                expected: limits.len(),
                actual: kf.positions.len(),
            });
        }
        check_keyframe(k, &kf.positions, limits)?;
        if let Some(at) = kf.at {
            if !at.is_finite() {
                return Err(PlanError::NotFinite {
                    keyframe: k,
                    joint: 0,
                });
            }
        }
    }
    if let Some(at) = keyframes[0].at {
        if at != 0.0 {
            return Err(PlanError::FirstKeyframeTime { at });
        }
    }
    Ok(())
}

fn expand<'a>(keyframes: &'a [Keyframe], options: &PlanOptions) -> Vec<Entry<'a>> {
    let timed_in_cycle = keyframes[1..].iter().any(|k| k.at.is_some());
    let closed =
        keyframes.len() > 1 && keyframes[0].positions == keyframes[keyframes.len() - 1].positions;
    let mut e = Vec::with_capacity(keyframes.len() * options.repeat as usize);
    for cycle in 0..options.repeat as usize {
        for (index, kf) in keyframes.iter().enumerate() {
            let shape = kf.shape.unwrap_or(options.shape);
            if index == 0 {
                if cycle == 0 {
                    e.push(Entry {
                        pos: &kf.positions,
                        at: Some(0.0),
                        shape,
                        index,
                        cycle,
                        rebase: true,
                        boundary: false,
                    });
                } else if closed {
                    // The previous cycle ended here: that arrival is this
                    // cycle's origin.
                    if let Some(last) = e.last_mut() {
                        last.rebase = true;
                        last.boundary |= timed_in_cycle && last.at.is_none();
                    }
                } else {
                    e.push(Entry {
                        pos: &kf.positions,
                        at: None,
                        shape,
                        index,
                        cycle,
                        rebase: true,
                        boundary: timed_in_cycle,
                    });
                }
            } else {
                e.push(Entry {
                    pos: &kf.positions,
                    at: kf.at,
                    shape,
                    index,
                    cycle,
                    rebase: false,
                    boundary: false,
                });
            }
        }
    }
    e
}

/// Plans a trajectory through `keyframes` under `limits`.
///
/// Consecutive timed keyframes are interpolated with their
/// [`TimedShape`]; untimed ones are passed through as fast as the limits
/// allow, all joints arriving at each keyframe together. Untimed keyframes
/// followed by a timed one are slowed down uniformly to arrive exactly on
/// time. Timed and untimed sections join at rest.
///
/// # Errors
///
/// Invalid limits or keyframes ([`PlanError::InvalidLimits`],
/// [`PlanError::WrongJointCount`], [`PlanError::NotFinite`],
/// [`PlanError::OutOfRange`], [`PlanError::FirstKeyframeTime`],
/// [`PlanError::TimeNotIncreasing`], [`PlanError::ZeroRepeat`]); a timed
/// segment beyond a limit ([`PlanError::LimitExceeded`],
/// [`PlanError::TooSoon`]) unless [`OnLimit::Stretch`] is set.
pub fn plan(
    limits: &[JointLimits],
    keyframes: &[Keyframe],
    options: &PlanOptions,
) -> Result<Trajectory, PlanError> {
    validate(limits, keyframes, options)?;
    let entries = expand(keyframes, options);
    let nj = limits.len();
    let mut out: Vec<Vec<Piece>> = (0..nj)
        .map(|_| Vec::with_capacity(entries.len() * 7))
        .collect();
    let mut arrival = vec![0.0; entries.len()];
    let mut scratch = Scratch::default();
    let mut pos: Vec<&[f64]> = Vec::with_capacity(entries.len());
    let mut times: Vec<f64> = Vec::with_capacity(entries.len());
    let (mut base, mut delay) = (0.0, 0.0);
    let last = entries.len() - 1;
    let mut i = 0;
    while i < last {
        pos.clear();
        times.clear();
        let j;
        if entries[i + 1].at.is_some() {
            // Timed section: consecutive timed entries.
            let mut k = i + 1;
            while k < last && entries[k + 1].at.is_some() {
                k += 1;
            }
            j = k;
            let (mut b, mut dl) = (base, delay);
            times.push(arrival[i]);
            for (k, e) in entries.iter().enumerate().take(j + 1).skip(i + 1) {
                let t = b + e.at.unwrap_or(0.0) + dl;
                let prev = times[times.len() - 1];
                if t <= prev {
                    return Err(PlanError::TimeNotIncreasing {
                        keyframe: e.index,
                        at: e.at.unwrap_or(0.0),
                        previous: prev - b - dl,
                    });
                }
                times.push(t);
                if entries[k].rebase {
                    b = t;
                    dl = 0.0;
                }
            }
            pos.extend(entries[i..=j].iter().map(|e| e.pos));
            timed_section(
                limits,
                &entries[i..=j],
                &pos,
                &mut times,
                options.on_limit,
                &mut out,
            )?;
            arrival[i..=j].copy_from_slice(&times);
        } else {
            // Untimed section: up to a timed entry, a boundary or the end.
            let mut k = i + 1;
            while k < last && entries[k + 1].at.is_none() && !entries[k].boundary {
                k += 1;
            }
            let anchored = k < last && entries[k + 1].at.is_some() && !entries[k].boundary;
            j = if anchored { k + 1 } else { k };
            pos.extend(entries[i..=j].iter().map(|e| e.pos));
            let start = arrival[i];
            let first_piece: Vec<usize> = out.iter().map(Vec::len).collect();
            untimed::section(
                limits,
                &pos,
                start,
                options.stop_at_keyframes,
                &mut scratch,
                &mut out,
            );
            let needed: f64 = scratch.durations.iter().sum();
            let mut scale = 1.0;
            if anchored {
                let target = base + entries[j].at.unwrap_or(0.0) + delay;
                let available = target - start;
                if needed > available * (1.0 + 1e-12) {
                    if options.on_limit == OnLimit::Error || available <= 0.0 && needed <= 0.0 {
                        return Err(PlanError::TooSoon {
                            keyframe: entries[j].index,
                            needed,
                            available,
                        });
                    }
                } else if needed > 0.0 {
                    scale = available / needed;
                } else if available > 0.0 {
                    // Nothing moves: hold until the keyframe's time.
                    scratch.durations[0] = available;
                    for (o, &f) in out.iter_mut().zip(&first_piece) {
                        for p in &mut o[f..] {
                            p.t1 = p.t0 + available;
                        }
                    }
                }
            }
            if scale != 1.0 {
                for (o, &f) in out.iter_mut().zip(&first_piece) {
                    for p in &mut o[f..] {
                        *p = p.stretched(start, scale);
                    }
                }
            }
            let mut t = start;
            for (k, d) in scratch.durations.iter().enumerate() {
                t += d * scale;
                arrival[i + 1 + k] = t;
            }
        }
        for e_k in i + 1..=j {
            let e = &entries[e_k];
            if e.rebase {
                base = arrival[e_k];
                delay = 0.0;
            } else if let Some(at) = e.at {
                delay = arrival[e_k] - (base + at);
            }
        }
        i = j;
    }
    let duration = arrival[last];
    let segments = (1..entries.len())
        .map(|k| SegmentTiming {
            keyframe: entries[k].index,
            cycle: entries[k].cycle,
            start: arrival[k - 1],
            end: arrival[k],
        })
        .collect();
    Ok(Trajectory::from_joints(
        out,
        entries[last].pos,
        duration,
        segments,
    ))
}

/// Worst limit ratio of a timed segment over all joints, as a time factor:
/// velocity scales as 1/s, acceleration 1/s^2 and jerk 1/s^3 when the
/// segment's time is stretched by s. Also returns the first violation.
fn check_segment(
    limits: &[JointLimits],
    pieces: &[Vec<Piece>],
    t0: f64,
    t1: f64,
    keyframe: usize,
) -> (f64, Option<PlanError>) {
    let mut factor: f64 = 1.0;
    let mut first = None;
    let tol = 1.0 + 1e-9;
    for (j, (ps, lim)) in pieces.iter().zip(limits).enumerate() {
        for p in ps.iter().filter(|p| {
            let mid = 0.5 * (p.t0 + p.t1);
            mid > t0 && mid < t1
        }) {
            let (lo, hi) = p.range(0);
            let checks = [
                (Quantity::Velocity, p.peak(1), lim.max_velocity, 1.0),
                (Quantity::Acceleration, p.peak(2), lim.max_acceleration, 2.0),
                (Quantity::Jerk, p.peak(3), lim.jerk(), 3.0),
            ];
            for (q, peak, limit, power) in checks {
                if peak > limit * tol {
                    factor = factor.max((peak / limit).powf(1.0 / power));
                    first.get_or_insert(PlanError::LimitExceeded {
                        keyframe,
                        joint: j,
                        quantity: q,
                        peak,
                        limit,
                    });
                }
            }
            let slack = 1e-9 * (1.0 + lim.max_position.abs().max(lim.min_position.abs()).min(1e12));
            let below = (lo < lim.min_position - slack).then_some((lo, lim.min_position));
            let above = (hi > lim.max_position + slack).then_some((hi, lim.max_position));
            if let Some((peak, limit)) = below.or(above) {
                // Position violations cannot be stretched away: report
                // them at once, with no factor.
                return (
                    f64::INFINITY,
                    Some(PlanError::LimitExceeded {
                        keyframe,
                        joint: j,
                        quantity: Quantity::Position,
                        peak,
                        limit,
                    }),
                );
            }
        }
    }
    (factor, first)
}

/// Local stretching rounds before the uniform stretch.
const LOCAL_ATTEMPTS: usize = 12;

/// Plans one timed section `entries[0..=m]` at `times` (updated in place
/// when stretched), splitting it into runs of equal shape.
fn timed_section(
    limits: &[JointLimits],
    entries: &[Entry<'_>],
    pos: &[&[f64]],
    times: &mut [f64],
    on_limit: OnLimit,
    out: &mut [Vec<Piece>],
) -> Result<(), PlanError> {
    let m = entries.len() - 1;
    let mut a = 0;
    let mut buf: Vec<Vec<Piece>> = vec![Vec::new(); limits.len()];
    while a < m {
        let shape = entries[a + 1].shape;
        let mut b = a + 1;
        while b < m && entries[b + 1].shape == shape {
            b += 1;
        }
        if shape == TimedShape::ShapePreserving {
            preserving_run(limits, entries, pos, times, a, b, on_limit, &mut buf)?;
            for (o, p) in out.iter_mut().zip(&mut buf) {
                o.append(p);
            }
            a = b;
            continue;
        }
        // Stretching loop: local stretching of offending segments first
        // (keeps the others on time), then one uniform stretch, which is
        // exact because a uniformly stretched run has the same shape (its
        // peaks scale by 1/s, 1/s^2, 1/s^3).
        let mut factors = vec![1.0f64; b - a];
        let mut attempt = 0;
        loop {
            buf.iter_mut().for_each(Vec::clear);
            spline::run(shape, &times[a..=b], &pos[a..=b], &mut buf);
            let mut worst: f64 = 1.0;
            let mut first_err = None;
            for k in a..b {
                let (f, e) =
                    check_segment(limits, &buf, times[k], times[k + 1], entries[k + 1].index);
                if let (Some(e), true) = (e, first_err.is_none() || f.is_infinite()) {
                    if f.is_infinite() {
                        return Err(e);
                    }
                    first_err = Some(e);
                }
                factors[k - a] = f;
                worst = worst.max(f);
            }
            let Some(err) = first_err else { break };
            if on_limit == OnLimit::Error || attempt > LOCAL_ATTEMPTS + 1 {
                return Err(err);
            }
            let uniform = attempt >= LOCAL_ATTEMPTS;
            attempt += 1;
            let mut shift = 0.0;
            let mut prev_old = times[a];
            for k in a..b {
                let h = times[k + 1] - prev_old;
                prev_old = times[k + 1];
                let f = if uniform { worst } else { factors[k - a] };
                let f = if f > 1.0 { f * (1.0 + 1e-6) } else { 1.0 };
                shift += h * (f - 1.0);
                times[k + 1] += shift;
            }
            // Everything after the run moves by the same amount.
            for t in &mut times[b + 1..] {
                *t += shift;
            }
        }
        for (o, p) in out.iter_mut().zip(&mut buf) {
            o.append(p);
        }
        a = b;
    }
    Ok(())
}

/// A shape-preserving run `a..=b` of a timed section: every segment too
/// short even for a rest-to-rest move is refused, or with
/// [`OnLimit::Stretch`] lengthened to the shortest such move (every later
/// keyframe delayed by as much); the others keep their times exactly.
#[allow(clippy::too_many_arguments)] // one run of the section's arrays
fn preserving_run(
    limits: &[JointLimits],
    entries: &[Entry<'_>],
    pos: &[&[f64]],
    times: &mut [f64],
    a: usize,
    b: usize,
    on_limit: OnLimit,
    buf: &mut [Vec<Piece>],
) -> Result<(), PlanError> {
    buf.iter_mut().for_each(Vec::clear);
    // One pass: lengthening segment `k` delays every later keyframe alike,
    // which leaves the later segments' durations as they were, so each
    // segment is checked once. `shift` is the delay carried so far.
    let mut shift = 0.0;
    for k in a..b {
        times[k + 1] += shift;
        let needed = timed::rest_to_rest(limits, pos, k);
        let available = times[k + 1] - times[k];
        if needed <= available * (1.0 + 1e-9) {
            continue;
        }
        if on_limit == OnLimit::Error {
            return Err(PlanError::TooSoon {
                keyframe: entries[k + 1].index,
                needed,
                available,
            });
        }
        let extra = needed * (1.0 + 1e-9) - available;
        times[k + 1] += extra;
        shift += extra;
    }
    for t in &mut times[b + 1..] {
        *t += shift;
    }
    timed::run(limits, &times[a..=b], &pos[a..=b], buf);
    Ok(())
}
