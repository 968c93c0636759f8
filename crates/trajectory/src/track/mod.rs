//! Recorded paths: a dense recording (a hand-guided take, a logged run)
//! played as a timed path through its samples, departing from it only
//! where it breaks a limit, and saying where and why.
//!
//! Method, per joint:
//!
//! 1. **Reference.** The C2 cubic spline through every sample at its time,
//!    at rest at both ends ([`TimedShape::Cubic`](crate::TimedShape)): the
//!    smoothest path that passes through the recording, with no filter,
//!    delay or resampling.
//! 2. **Forward pass.** A step at a time, the reference's own pieces where
//!    they keep within the velocity, acceleration, jerk and position
//!    limits (and end where the joint can still keep within them);
//!    elsewhere a time-optimal pursuit of the reference that rejoins it
//!    exactly as soon as the limits let it (`pass`). It is exactly the
//!    recording where the recording is within the limits, and late where
//!    it is not: it only reacts to what it has reached.
//! 3. **Backward pass.** The same on the reference played backwards: in
//!    forward time it is early by about as much where it departs.
//! 4. **Average.** The path is the mean of the two. Velocity, acceleration
//!    and jerk limits are symmetric bounds, so the mean of two paths within
//!    them is within them too; where both are on the reference, so is the
//!    mean; where the recording breaks a limit, the lateness of one and
//!    the earliness of the other cancel (exactly so for a steady ramp). It
//!    starts at rest at the recording's first position and ends at rest at
//!    its last.
//!
//! Nothing is smoothed that the limits allow: the departures are exactly
//! the stretches where one pass or the other had to leave the recording,
//! each with the limit the recording breaks there ([`Departure`]). Rounding
//! in a recording's numbers also breaks a limit now and then, by a hair
//! and for a step, which costs a departure far below any servo's
//! resolution: a caller says which departures are worth showing.

mod pass;
mod reference;
mod report;

use crate::error::{PlanError, Quantity};
use crate::limits::{check_keyframe, validate_all};
use crate::online::finish;
use crate::piece::Piece;
use crate::{JointLimits, Trajectory};
use pass::Reference;

/// A recording played by [`track`], with how far it departs from the
/// recording, where and why.
#[derive(Debug, Clone)]
pub struct Tracked {
    /// The path, from rest at the first sample to rest at the last.
    pub trajectory: Trajectory,
    /// Time in the path of the recording's first sample, s: the path
    /// starts moving this much earlier when the recording starts with more
    /// than the limits allow from rest (0 for one that starts at rest).
    pub recording_start: f64,
    /// Per joint, the largest distance between the path and the recording
    /// at the recording's samples.
    pub max_deviation: Vec<f64>,
    /// Per joint, the root mean square of that distance over the samples.
    pub rms_deviation: Vec<f64>,
    /// Every stretch where the path leaves the recording, by joint then
    /// time, however small (see the module documentation).
    pub departures: Vec<Departure>,
}

/// A stretch of one joint's path off the recording, and why: the limit
/// the recording breaks there.
#[derive(Debug, Clone, PartialEq)]
pub struct Departure {
    /// Joint index.
    pub joint: usize,
    /// Start and end of the stretch, s, in the recording's time (as its
    /// samples' times are given). The path leaves the recording a little
    /// before the place it breaks the limit, to keep to it on time.
    pub start: f64,
    /// End of the stretch, s (recording time).
    pub end: f64,
    /// The limit the recording breaks in the stretch: of those it breaks,
    /// the one of lowest order (position, then velocity, acceleration,
    /// jerk), the cause of the others.
    pub quantity: Quantity,
    /// The recording's peak of that quantity in the stretch (as a
    /// magnitude; a position for [`Quantity::Position`]).
    pub peak: f64,
    /// The limit it breaks.
    pub limit: f64,
    /// The largest distance between the path and the recording's samples
    /// in the stretch.
    pub max_departure: f64,
    /// When it is, s (recording time).
    pub at: f64,
}

/// Options of [`track_with`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackOptions {
    /// The tracking step, s (the control period is a good choice; not
    /// finite or not positive: 5 ms).
    pub step: f64,
    /// The largest rounding error of a sample's numbers, in the samples'
    /// unit (half a unit of the last decimal written: 0.00005 for numbers
    /// with four decimals); 0 for exact numbers. Differences of samples
    /// within this of each other cannot be told apart, so the recording is
    /// followed where it keeps within the limits widened by what that
    /// rounding makes of its differences: `2 r / h` in speed, `4 r / h^2`
    /// in acceleration, `8 r / h^3` in jerk, samples `h` apart.
    pub resolution: f64,
}

impl Default for TrackOptions {
    fn default() -> Self {
        TrackOptions {
            step: 0.005,
            resolution: 0.0,
        }
    }
}

/// Plays a recording (`times[i]` in s, increasing; `samples[i][j]` the
/// position of joint `j` then) as a path within `limits` through its
/// samples, tracked in steps of `step` s (the control period is a good
/// choice); its numbers taken as exact ([`track_with`] says otherwise).
///
/// # Errors
///
/// As [`track_with`].
pub fn track(
    limits: &[JointLimits],
    times: &[f64],
    samples: &[Vec<f64>],
    step: f64,
) -> Result<Tracked, PlanError> {
    let options = TrackOptions {
        step,
        ..TrackOptions::default()
    };
    track_with(limits, times, samples, &options)
}

/// [`track`] with its options.
///
/// # Errors
///
/// Invalid limits; fewer than two samples, times not increasing or not
/// finite, a sample of the wrong length ([`PlanError::WrongJointCount`]),
/// not finite or outside the position limits ([`PlanError::OutOfRange`],
/// with the sample's index as `keyframe`).
pub fn track_with(
    limits: &[JointLimits],
    times: &[f64],
    samples: &[Vec<f64>],
    options: &TrackOptions,
) -> Result<Tracked, PlanError> {
    validate(limits, times, samples)?;
    let step = if options.step.is_finite() && options.step > 0.0 {
        options.step
    } else {
        TrackOptions::default().step
    };
    let t0 = times[0];
    let rel: Vec<f64> = times.iter().map(|t| t - t0).collect();
    let end = rel[rel.len() - 1];
    let grid = reference::Grid::of(&rel, samples);
    let resolution = if options.resolution.is_finite() {
        options.resolution.max(0.0)
    } else {
        0.0
    };
    let setup = Setup {
        grid,
        samples,
        end,
        step,
        resolution,
    };

    let mut reference = Vec::with_capacity(limits.len());
    let mut per_joint = Vec::with_capacity(limits.len());
    let mut off = Vec::with_capacity(limits.len());
    let mut lead = Vec::with_capacity(limits.len());
    let mut shown = Vec::with_capacity(limits.len());
    let mut tail: f64 = 0.0;
    for (j, lim) in limits.iter().enumerate() {
        let joint = setup.track_joint(j, lim)?;
        per_joint.push(joint.pieces);
        off.push(joint.off);
        lead.push(joint.lead);
        tail = tail.max(joint.tail);
        reference.push(joint.reference);
        shown.push(joint.shown);
    }
    // Every joint starts at the same instant: the earliest start.
    let shift = lead.iter().copied().fold(0.0, f64::max);
    let duration = shift + tail;
    align_starts(&mut per_joint, &lead, shift, &samples[0]);
    // Every joint then rests at the recording's last position until the
    // slowest one is done.
    let trajectory = finish(per_joint, &samples[samples.len() - 1], duration);
    check_positions(limits, &trajectory)?;
    let errors = report::errors(&trajectory, &rel, samples, shift);
    let (max_deviation, rms_deviation) = report::summary(&errors, limits.len());
    let context = report::Context {
        limits,
        shown: &shown,
        reference: &reference,
        rel: &rel,
        t0,
    };
    let departures = report::departures(&context, &errors, &mut off);
    Ok(Tracked {
        trajectory,
        recording_start: shift,
        max_deviation,
        rms_deviation,
        departures,
    })
}

/// What every joint's passes share: the recording and how it is tracked.
struct Setup<'a> {
    /// The samples on their grid.
    grid: reference::Grid,
    /// The samples as given.
    samples: &'a [Vec<f64>],
    /// The recording's last time, s from its first.
    end: f64,
    /// The tracking step, s.
    step: f64,
    /// The samples' rounding error (finite, at least 0).
    resolution: f64,
}

/// One joint's path before the joints are aligned, and what the report
/// needs of it.
struct JointTrack {
    /// The reference spline it tracks.
    reference: Vec<Piece>,
    /// The mean of the two passes, starting at `-lead`.
    pieces: Vec<Piece>,
    /// The stretches where either pass left the reference (recording time).
    off: Vec<(f64, f64)>,
    /// How long before the recording's first sample the path starts, s.
    lead: f64,
    /// When the path ends, s (recording time).
    tail: f64,
    /// The limits widened by the samples' rounding.
    shown: JointLimits,
}

impl Setup<'_> {
    /// Tracks joint `j` within `lim`: the reference, its forward and
    /// backward passes, and their mean.
    fn track_joint(&self, j: usize, lim: &JointLimits) -> Result<JointTrack, PlanError> {
        let (end, step, samples) = (self.end, self.step, self.samples);
        let lims = pass::Limits {
            strict: *lim,
            shown: widened(lim, self.resolution, self.grid.h),
        };
        let mut forward = reference::build(&self.grid, j, &lims.shown);
        if let Some(last) = forward.last_mut() {
            last.t1 = end;
        }
        let backward: Vec<Piece> = forward.iter().rev().map(|p| p.mirrored(end)).collect();
        let (first, last) = (samples[0][j], samples[samples.len() - 1][j]);
        let f = pass::run(&lims, &Reference::new(&forward, end), step, (first, last))?;
        let b = pass::run(&lims, &Reference::new(&backward, end), step, (last, first))?;
        // The backward pass, in forward time, spans [end - b_len, end].
        let b_len = b.pieces.last().map_or(0.0, |p| p.t1);
        let f_len = f.pieces.last().map_or(0.0, |p| p.t1);
        let start = (end - b_len).min(0.0);
        let b_fwd: Vec<Piece> = b.pieces.iter().rev().map(|p| p.mirrored(end)).collect();
        let pieces = average(&f.pieces, &b_fwd, start, f_len.max(end));
        let mut stretches = f.off;
        stretches.extend(b.off.iter().map(|&(a, z)| (end - z, end - a)));
        Ok(JointTrack {
            reference: forward,
            pieces,
            off: stretches,
            lead: -start,
            tail: f_len.max(end),
            shown: lims.shown,
        })
    }
}

/// Moves every joint's path (joint `j` starting `lead[j]` before the
/// recording) to start at 0 with the recording at `shift`, holding the
/// first sample `first` until a joint starts moving.
fn align_starts(per_joint: &mut [Vec<Piece>], lead: &[f64], shift: f64, first: &[f64]) {
    for (j, (pieces, &l)) in per_joint.iter_mut().zip(lead).enumerate() {
        let offset = shift - l;
        let mut shifted = Vec::with_capacity(pieces.len() + 2);
        if offset > 0.0 {
            shifted.push(Piece::hold(0.0, offset, first[j]));
        }
        shifted.extend(pieces.iter().map(|p| Piece {
            t0: p.t0 + l + offset,
            t1: p.t1 + l + offset,
            c: p.c,
        }));
        *pieces = shifted;
    }
}

/// `lim` widened by what a rounding of `resolution` makes of the
/// differences of samples `h` apart.
fn widened(lim: &JointLimits, resolution: f64, h: f64) -> JointLimits {
    let r = resolution;
    JointLimits {
        max_velocity: lim.max_velocity + 2.0 * r / h,
        max_acceleration: lim.max_acceleration + 4.0 * r / (h * h),
        max_jerk: lim.max_jerk.map(|jm| jm + 8.0 * r / (h * h * h)),
        ..*lim
    }
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

/// The mean of two piecewise-polynomial paths over `[from, to]`, each held
/// at its end position outside its pieces (at rest, by construction).
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
        let ca = about(a, &mut ia, mid, u0);
        let cb = about(b, &mut ib, mid, u0);
        let mut c = [0.0; 6];
        for k in 0..6 {
            c[k] = 0.5 * (ca[k] + cb[k]);
        }
        out.push(Piece { t0: u0, t1: u1, c });
    }
    out
}

/// Coefficients, about `at`, of the piece of `ps` holding `mid` (`i`: a
/// cursor moving forward); outside the pieces, the held end.
fn about(ps: &[Piece], i: &mut usize, mid: f64, at: f64) -> [f64; 6] {
    while *i + 1 < ps.len() && ps[*i].t1 < mid {
        *i += 1;
    }
    let Some(p) = ps.get(*i) else {
        return [0.0; 6];
    };
    let held = |x: f64| [p.eval_local(x).0, 0.0, 0.0, 0.0, 0.0, 0.0];
    if mid < p.t0 {
        held(0.0)
    } else if mid > p.t1 {
        held(p.duration())
    } else {
        p.about(at)
    }
}

/// A guard: the passes keep their quickest stops inside the position
/// limits, so the path never leaves them.
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
