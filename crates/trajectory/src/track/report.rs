//! How far a played recording is from the recording, and where and why it
//! departs.

use super::Departure;
use crate::error::Quantity;
use crate::piece::Piece;
use crate::{JointLimits, JointState, Trajectory};

/// Relative slack on a limit before the recording is said to break it.
const SLACK: f64 = 1e-9;

/// The path's distance from every sample (`errors[i][j]`, signed), the
/// recording's sample `i` at time `rel[i]` from its first, the path
/// shifted by `shift`.
pub(super) fn errors(
    t: &Trajectory,
    rel: &[f64],
    samples: &[Vec<f64>],
    shift: f64,
) -> Vec<Vec<f64>> {
    let n = t.joints();
    let mut out = vec![JointState::default(); n];
    let mut cursor = t.cursor();
    rel.iter()
        .zip(samples)
        .map(|(&x, s)| {
            t.sample_with(&mut cursor, shift + x, &mut out);
            out.iter().zip(s).map(|(o, &q)| o.position - q).collect()
        })
        .collect()
}

/// Max and RMS distance per joint.
pub(super) fn summary(errors: &[Vec<f64>], n: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut max, mut sum) = (vec![0.0f64; n], vec![0.0; n]);
    for row in errors {
        for (j, e) in row.iter().enumerate() {
            max[j] = max[j].max(e.abs());
            sum[j] += e * e;
        }
    }
    let count = errors.len().max(1) as f64;
    let rms = sum.iter().map(|s| (s / count).sqrt()).collect();
    (max, rms)
}

/// What the departures are measured against: the joints' limits, and as
/// the recording can show them, the reference paths, the samples' times
/// from the first (`rel`) and the first's (`t0`).
pub(super) struct Context<'a> {
    pub limits: &'a [JointLimits],
    pub shown: &'a [JointLimits],
    pub reference: &'a [Vec<Piece>],
    pub rel: &'a [f64],
    pub t0: f64,
}

/// The departures of every joint: its stretches off the reference
/// (`off[j]`, from either pass, in time from the first sample) merged
/// where they overlap, each with the limit the reference breaks there and
/// the largest error at a sample in it. Times in the result are the
/// recording's.
pub(super) fn departures(
    cx: &Context,
    errors: &[Vec<f64>],
    off: &mut [Vec<(f64, f64)>],
) -> Vec<Departure> {
    let rel = cx.rel;
    let mut out = Vec::new();
    for (j, stretches) in off.iter_mut().enumerate() {
        stretches.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut merged: Vec<(f64, f64)> = Vec::with_capacity(stretches.len());
        for &(a, b) in stretches.iter() {
            match merged.last_mut() {
                Some(last) if a <= last.1 => last.1 = last.1.max(b),
                _ => merged.push((a, b)),
            }
        }
        for (a, b) in merged {
            let (quantity, peak, limit) =
                broken(&cx.limits[j], &cx.shown[j], &cx.reference[j], a, b);
            // The largest error at a sample in the stretch.
            let first = rel.partition_point(|&x| x < a);
            let last = rel.partition_point(|&x| x <= b);
            let (mut max_departure, mut at) = (0.0f64, a.max(0.0));
            for i in first..last {
                let e = errors[i][j].abs();
                if e > max_departure {
                    (max_departure, at) = (e, rel[i]);
                }
            }
            out.push(Departure {
                joint: j,
                start: cx.t0 + a,
                end: cx.t0 + b,
                quantity,
                peak,
                limit,
                max_departure,
                at: cx.t0 + at,
            });
        }
    }
    out
}

/// The limit the reference breaks over `[a, b]`: of those it breaks
/// (beyond `shown`, the limits as the recording can show them), the lowest
/// order one; if none (the reference only ends somewhere the joint could
/// not keep within them), the one it comes nearest to. With its peak and
/// the joint's limit.
fn broken(
    lim: &JointLimits,
    shown: &JointLimits,
    reference: &[Piece],
    a: f64,
    b: f64,
) -> (Quantity, f64, f64) {
    let end = reference.last().map_or(0.0, |p| p.t1);
    let (a, b) = (a.clamp(0.0, end), b.clamp(0.0, end));
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut peaks = [0.0f64; 3];
    let first = reference.partition_point(|p| p.t1 < a);
    for p in reference[first..].iter().take_while(|p| p.t0 <= b) {
        let u0 = a.max(p.t0);
        let part = p.part(u0, b.min(p.t1).max(u0));
        let (l, h) = part.range(0);
        lo = lo.min(l);
        hi = hi.max(h);
        for (k, peak) in peaks.iter_mut().enumerate() {
            *peak = peak.max(part.peak(k + 1));
        }
    }
    if lo < lim.min_position - SLACK * (1.0 + lim.min_position.abs()) {
        return (Quantity::Position, lo, lim.min_position);
    }
    if hi > lim.max_position + SLACK * (1.0 + lim.max_position.abs()) {
        return (Quantity::Position, hi, lim.max_position);
    }
    let bounds = [
        (Quantity::Velocity, lim.max_velocity, shown.max_velocity),
        (
            Quantity::Acceleration,
            lim.max_acceleration,
            shown.max_acceleration,
        ),
        (
            Quantity::Jerk,
            lim.max_jerk.unwrap_or(f64::INFINITY),
            shown.max_jerk.unwrap_or(f64::INFINITY),
        ),
    ];
    let over = (0..3).find(|&k| peaks[k] > bounds[k].2 * (1.0 + SLACK));
    let k = over.unwrap_or_else(|| {
        (0..3)
            .max_by(|&x, &y| (peaks[x] / bounds[x].1).total_cmp(&(peaks[y] / bounds[y].1)))
            .unwrap_or(0)
    });
    (bounds[k].0, peaks[k], bounds[k].1)
}
