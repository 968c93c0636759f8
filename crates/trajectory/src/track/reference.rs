//! The reference path of a recording: a uniform cubic B-spline through its
//! samples, at rest at both ends.
//!
//! A cubic B-spline's speed, acceleration and jerk are weighted means
//! (non-negative weights summing to one) of its control points' first,
//! second and third differences. With the samples themselves as control
//! points it is therefore within every limit wherever the samples'
//! differences are, which they are for any path within the limits that
//! they were sampled from (up to the rounding of their numbers). It passes
//! close to them, not through them: by `a h^2 / 6` at an acceleration `a`
//! (0.005 deg at 1200 deg/s^2 and 200 Hz). The control points that make
//! it pass through every sample (the interpolating cubic spline) are used
//! instead where that keeps within the limits too, as it does for sparse
//! samples of a smooth path; but where the path they were sampled from
//! switches its jerk between two samples, as a time-optimal motion does,
//! the interpolating spline rings to up to twice the jerk limit. Mixing
//! the two would add the mixing's own acceleration, so each joint has one
//! kind or the other.
//!
//! ```text
//!  control points   c[-1] = q[0]   c[0] .. c[K]   c[K+1] = q[K]
//!  segment k        [t_k, t_k+1] from c[k-1], c[k], c[k+1], c[k+2]
//! ```
//!
//! The first and last samples are held one interval beyond the ends (a
//! recording starts and ends at rest), and a short quintic correction of
//! the first and last few intervals brings the path to rest exactly at
//! them.

use crate::piece::Piece;
use crate::JointLimits;

/// A recording on a uniform grid: `values[k][j]` at `k h` from its start.
pub(super) struct Grid {
    pub h: f64,
    pub values: Vec<Vec<f64>>,
}

impl Grid {
    /// The samples as they are when they are evenly spaced (to a
    /// millionth of their spacing), else resampled at their median spacing
    /// (linearly), with at least four intervals.
    pub fn of(rel: &[f64], samples: &[Vec<f64>]) -> Grid {
        let end = rel[rel.len() - 1];
        let n = rel.len() - 1;
        let even = |h: f64| {
            rel.iter()
                .enumerate()
                .all(|(k, &t)| (t - k as f64 * h).abs() <= 1e-6 * h)
        };
        let h = end / n as f64;
        if n >= 4 && even(h) {
            return Grid {
                h,
                values: samples.to_vec(),
            };
        }
        let mut spacing: Vec<f64> = rel.windows(2).map(|w| w[1] - w[0]).collect();
        spacing.sort_by(f64::total_cmp);
        let median = spacing[spacing.len() / 2];
        let k = ((end / median).round() as usize).max(4);
        let h = end / k as f64;
        let values = (0..=k)
            .map(|i| {
                let t = (i as f64 * h).min(end);
                let at = rel.partition_point(|&x| x <= t).clamp(1, n);
                let (ta, tb) = (rel[at - 1], rel[at]);
                let w = if tb > ta { (t - ta) / (tb - ta) } else { 1.0 };
                samples[at - 1]
                    .iter()
                    .zip(&samples[at])
                    .map(|(a, b)| a + (b - a) * w.clamp(0.0, 1.0))
                    .collect()
            })
            .collect();
        Grid { h, values }
    }
}

/// Joint `j`'s reference over `[0, K h]`: its pieces, one per interval,
/// at rest at its first and last samples where a short end correction
/// keeps within `lim` (the limits as the recording can show them).
pub(super) fn build(grid: &Grid, j: usize, lim: &JointLimits) -> Vec<Piece> {
    let q: Vec<f64> = grid.values.iter().map(|row| row[j]).collect();
    let k = q.len() - 1;
    let through = interpolating(&q);
    let mut pieces = segments(&controls(&q, &through), grid.h);
    if !pieces.iter().all(|p| within(lim, p)) {
        // Blending the two kinds of control points would add the blend's
        // own acceleration: one or the other for the whole joint.
        pieces = segments(&controls(&q, &q), grid.h);
    }
    rest_ends(&mut pieces, (q[0], q[k]), lim);
    pieces
}

/// Control points `c[-1..=K+1]` (from index 0): `c[0..=K]` as given, the
/// first and last samples held one interval beyond the ends (at rest
/// before and after).
fn controls(q: &[f64], c: &[f64]) -> Vec<f64> {
    let k = q.len() - 1;
    std::iter::once(q[0])
        .chain(c.iter().copied())
        .chain(std::iter::once(q[k]))
        .collect()
}

/// Corrects the first and last few pieces so that the path starts at rest
/// at `first` and ends at rest at `last` exactly: the shortest quintic
/// correction of [`END_STEPS`] intervals that keeps within `lim` (none when
/// none does: the passes then start and end off the reference).
fn rest_ends(pieces: &mut [Piece], (first, last): (f64, f64), lim: &JointLimits) {
    let n = pieces.len();
    let end = pieces[n - 1].t1;
    for at_end in [false, true] {
        let mut span: Vec<Piece> = if at_end {
            pieces.iter().rev().map(|p| p.mirrored(end)).collect()
        } else {
            pieces.to_vec()
        };
        let (p, v, a) = span[0].eval_local(0.0);
        let target = if at_end { last } else { first };
        let e = crate::JointState {
            position: target - p,
            velocity: -v,
            acceleration: -a,
        };
        for m in END_STEPS.into_iter().filter(|&m| m <= n) {
            let t1 = span[m - 1].t1;
            let correction = Piece {
                t0: 0.0,
                t1,
                c: super::pass::blend(&e, t1),
            };
            let fixed: Vec<Piece> = span[..m]
                .iter()
                .map(|p| {
                    let mut q = *p;
                    for (qc, dc) in q.c.iter_mut().zip(correction.about(p.t0)) {
                        *qc += dc;
                    }
                    q
                })
                .collect();
            if fixed.iter().all(|p| within(lim, p)) {
                span[..m].copy_from_slice(&fixed);
                break;
            }
        }
        if at_end {
            for (slot, p) in pieces.iter_mut().zip(span.iter().rev()) {
                *slot = p.mirrored(end);
            }
        } else {
            pieces.copy_from_slice(&span);
        }
    }
}

/// Lengths, in intervals, of the end corrections tried, shortest first.
const END_STEPS: [usize; 8] = [1, 2, 3, 4, 6, 8, 12, 16];

/// The control points `c[0..=K]` of the B-spline through every sample
/// (the held ones beyond the ends as above): `c[k-1] + 4 c[k] + c[k+1] =
/// 6 q[k]`, tridiagonal (Thomas; diagonally dominant).
fn interpolating(q: &[f64]) -> Vec<f64> {
    let n = q.len();
    let mut cp = vec![0.0; n];
    let mut d = vec![0.0; n];
    for r in 0..n {
        let mut rhs = 6.0 * q[r];
        if r == 0 {
            rhs -= q[0];
        }
        if r == n - 1 {
            rhs -= q[n - 1];
        }
        let den = 4.0 - if r > 0 { cp[r - 1] } else { 0.0 };
        cp[r] = 1.0 / den;
        d[r] = (rhs - if r > 0 { d[r - 1] } else { 0.0 }) / den;
    }
    let mut c = vec![0.0; n];
    for r in (0..n).rev() {
        let next = if r + 1 < n { c[r + 1] } else { 0.0 };
        c[r] = d[r] - cp[r] * next;
    }
    c
}

/// The pieces of the uniform B-spline of `controls` (`c[-1..=K+1]` from
/// index 0) with knots `h` apart.
fn segments(controls: &[f64], h: f64) -> Vec<Piece> {
    let k = controls.len() - 3;
    (0..k)
        .map(|s| {
            let (a, b, c, d) = (
                controls[s],
                controls[s + 1],
                controls[s + 2],
                controls[s + 3],
            );
            let t0 = s as f64 * h;
            Piece {
                t0,
                t1: if s + 1 == k { k as f64 * h } else { t0 + h },
                c: [
                    (a + 4.0 * b + c) / 6.0,
                    (c - a) / (2.0 * h),
                    (a - 2.0 * b + c) / (2.0 * h * h),
                    (-a + 3.0 * b - 3.0 * c + d) / (6.0 * h * h * h),
                    0.0,
                    0.0,
                ],
            }
        })
        .collect()
}

/// Whether piece `p` keeps within `lim` (with rounding slack).
fn within(lim: &JointLimits, p: &Piece) -> bool {
    let tol = 1.0 + 1e-9;
    let (lo, hi) = p.range(0);
    p.peak(1) <= lim.max_velocity * tol
        && p.peak(2) <= lim.max_acceleration * tol
        && lim.max_jerk.is_none_or(|jm| p.peak(3) <= jm * tol)
        && lo >= lim.min_position
        && hi <= lim.max_position
}
