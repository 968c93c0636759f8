//! Timed keyframes: interpolation through positions at fixed times.
//!
//! Every run of timed segments with the same [`TimedShape`] starts and ends
//! at rest (zero velocity and acceleration), so runs join with continuous
//! velocity and acceleration whatever their shapes.

use crate::piece::Piece;

/// How timed keyframes are interpolated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum TimedShape {
    /// Shape-preserving jerk-limited segments (the default): each joint
    /// stays within the range of the two keyframes around every segment,
    /// passes a keyframe where it turns back at zero speed, and keeps
    /// velocity and acceleration continuous. Every motion that stopping at
    /// each keyframe at its time could do is planned, at exactly its times
    /// and within every limit (see `timed.rs`).
    #[default]
    ShapePreserving,
    /// A C2 cubic spline through every keyframe (the smoothest: continuous
    /// acceleration, piecewise-constant jerk), at rest at both ends of the
    /// run. Two extra knots, in the middle of the first and last intervals,
    /// give the freedom to start and end with zero acceleration too. It may
    /// overshoot between keyframes, and is refused where it breaks a limit.
    Cubic,
    /// Quintic Hermite segments that never overshoot: each segment is
    /// monotone between its keyframes. Velocity at a keyframe is zero where
    /// the joint turns back and the harmonic mean of the neighbouring average
    /// speeds elsewhere (at most twice the smaller one, which keeps the
    /// quintic monotone); acceleration is zero at every keyframe.
    Monotone,
    /// Minimum-jerk quintic segments, at rest at every keyframe.
    MinimumJerk,
}

/// Quintic with zero acceleration at both ends from `(q0, v0)` to
/// `(q0 + dq, v1)` over `h`.
fn quintic(t0: f64, h: f64, q0: f64, dq: f64, v0: f64, v1: f64) -> Piece {
    let (h2, h3) = (h * h, h * h * h);
    Piece {
        t0,
        t1: t0 + h,
        c: [
            q0,
            v0,
            0.0,
            (20.0 * dq - (8.0 * v1 + 12.0 * v0) * h) / (2.0 * h3),
            (-30.0 * dq + (14.0 * v1 + 16.0 * v0) * h) / (2.0 * h3 * h),
            (12.0 * dq - 6.0 * (v1 + v0) * h) / (2.0 * h3 * h2),
        ],
    }
}

/// Builds the pieces of one run: `times[k]` and `pos[k]` (one position per
/// joint) for `k = 0..=m`, times strictly increasing. Appends to `out[j]`.
/// [`TimedShape::ShapePreserving`] is planned by `timed::run` instead
/// (it needs the limits).
pub(crate) fn run(shape: TimedShape, times: &[f64], pos: &[&[f64]], out: &mut [Vec<Piece>]) {
    match shape {
        TimedShape::MinimumJerk => {
            for (j, o) in out.iter_mut().enumerate() {
                for k in 0..times.len() - 1 {
                    let h = times[k + 1] - times[k];
                    o.push(quintic(
                        times[k],
                        h,
                        pos[k][j],
                        pos[k + 1][j] - pos[k][j],
                        0.0,
                        0.0,
                    ));
                }
            }
        }
        TimedShape::Monotone => {
            let m = times.len() - 1;
            for (j, o) in out.iter_mut().enumerate() {
                let slope = |k: usize| (pos[k + 1][j] - pos[k][j]) / (times[k + 1] - times[k]);
                let vel = |k: usize| {
                    if k == 0 || k == m {
                        return 0.0;
                    }
                    let (a, b) = (slope(k - 1), slope(k));
                    if a * b <= 0.0 {
                        0.0
                    } else {
                        2.0 * a * b / (a + b)
                    }
                };
                let mut v0 = 0.0;
                for k in 0..m {
                    let v1 = vel(k + 1);
                    let h = times[k + 1] - times[k];
                    o.push(quintic(
                        times[k],
                        h,
                        pos[k][j],
                        pos[k + 1][j] - pos[k][j],
                        v0,
                        v1,
                    ));
                    v0 = v1;
                }
            }
        }
        TimedShape::Cubic | TimedShape::ShapePreserving => cubic(times, pos, out),
    }
}

/// Cubic spline through the keyframes with zero velocity and acceleration at
/// both ends. Unknowns are the second derivatives `M` at the knots; the two
/// extra knots' positions are eliminated through the end conditions
/// (`v = 0` gives `q_1 = q_0 + h_0^2 M_1 / 6`, likewise at the end), which
/// keeps the system tridiagonal. The matrix depends only on the times, so
/// it is factored once for all joints.
fn cubic(times: &[f64], pos: &[&[f64]], out: &mut [Vec<Piece>]) {
    let system = CubicSystem::new(times);
    let m = system.tau.len() - 1;
    let mut rhs = vec![0.0; m - 1];
    let mut mm = vec![0.0; m + 1];
    let mut q = vec![0.0; m + 1];
    for (j, o) in out.iter_mut().enumerate() {
        system.solve(pos, j, &mut q, &mut rhs, &mut mm);
        system.push_pieces(&q, &mm, o);
    }
}

/// Index of the first extra knot (the second knot).
const FIRST_EXTRA: usize = 1;

/// The knots of a cubic run and its factored tridiagonal system, shared by
/// all joints. Rows `r = 0..n` are for knots `k = r + 1`, the unknowns
/// `M_1..M_{m-1}` for knots `0..=m`.
struct CubicSystem {
    /// Knot times: the keyframes plus two extra knots.
    tau: Vec<f64>,
    /// Which keyframe each knot is (None for the extra ones).
    kf: Vec<Option<usize>>,
    /// Index of the last keyframe.
    last_keyframe: usize,
    /// Knot intervals, `h[i] = tau[i + 1] - tau[i]`.
    h: Vec<f64>,
    /// Sub-diagonal of the eliminated system.
    sub: Vec<f64>,
    /// Thomas factorisation: modified super-diagonal.
    cp: Vec<f64>,
    /// Thomas factorisation: pivots.
    den: Vec<f64>,
    /// The first extra knot is `q_0 + s0 * M_1`.
    s0: f64,
    /// The last extra knot is `q_m + sm * M_{m-1}`.
    sm: f64,
}

impl CubicSystem {
    /// Places the knots for `times` and factors the system.
    fn new(times: &[f64]) -> Self {
        let (tau, kf) = cubic_knots(times);
        let m = tau.len() - 1; // knots 0..=m, unknowns M_1..M_{m-1}
        let h: Vec<f64> = tau.windows(2).map(|w| w[1] - w[0]).collect();
        let n = m - 1;
        let s0 = h[0] * h[0] / 6.0;
        let sm = h[m - 1] * h[m - 1] / 6.0;
        let [sub, diag, sup] = cubic_matrix(&h, s0, sm);
        // Thomas factorisation (the system is diagonally dominant after the
        // elimination: the extra knots split intervals in equal halves).
        let mut cp = vec![0.0; n];
        let mut den = vec![0.0; n];
        for r in 0..n {
            let d = diag[r] - if r > 0 { sub[r] * cp[r - 1] } else { 0.0 };
            den[r] = d;
            cp[r] = sup[r] / d;
        }
        CubicSystem {
            tau,
            kf,
            last_keyframe: times.len() - 1,
            h,
            sub,
            cp,
            den,
            s0,
            sm,
        }
    }

    /// Solves joint `j`: knot positions into `q`, second derivatives into
    /// `mm` (`rhs` is scratch).
    fn solve(&self, pos: &[&[f64]], j: usize, q: &mut [f64], rhs: &mut [f64], mm: &mut [f64]) {
        let m = self.tau.len() - 1;
        let n = m - 1;
        let last_extra = m - 1;
        let (h, sub) = (&self.h, &self.sub);
        let p0 = pos[0][j];
        let pm = pos[self.last_keyframe][j];
        for (k, slot) in q.iter_mut().enumerate() {
            // Extra knots use their anchor for now (the M part was moved).
            *slot = match self.kf[k] {
                Some(i) => pos[i][j],
                None if k == FIRST_EXTRA => p0,
                None => pm,
            };
        }
        for r in 0..n {
            let k = r + 1;
            let v = cubic_coef(h, k, k - 1) * q[k - 1]
                + cubic_coef(h, k, k) * q[k]
                + cubic_coef(h, k, k + 1) * q[k + 1];
            rhs[r] = (v - if r > 0 { sub[r] * rhs[r - 1] } else { 0.0 }) / self.den[r];
        }
        for r in (0..n).rev() {
            let next = if r + 1 < n { mm[r + 2] } else { 0.0 };
            mm[r + 1] = rhs[r] - self.cp[r] * next;
        }
        mm[0] = 0.0;
        mm[m] = 0.0;
        q[FIRST_EXTRA] = p0 + self.s0 * mm[FIRST_EXTRA];
        q[last_extra] = pm + self.sm * mm[last_extra];
    }

    /// Appends one cubic piece per knot interval from the solved `q` and `mm`.
    fn push_pieces(&self, q: &[f64], mm: &[f64], o: &mut Vec<Piece>) {
        let tau = &self.tau;
        for (i, &hi) in self.h.iter().enumerate() {
            o.push(Piece {
                t0: tau[i],
                t1: tau[i + 1],
                c: [
                    q[i],
                    (q[i + 1] - q[i]) / hi - hi * (2.0 * mm[i] + mm[i + 1]) / 6.0,
                    0.5 * mm[i],
                    (mm[i + 1] - mm[i]) / (6.0 * hi),
                    0.0,
                    0.0,
                ],
            });
        }
    }
}

/// The cubic run's knot times and which keyframe each knot is: the
/// keyframes plus an extra knot in the first and in the last interval
/// (thirds of the only interval when there is one).
fn cubic_knots(times: &[f64]) -> (Vec<f64>, Vec<Option<usize>>) {
    let m_kf = times.len() - 1;
    let mut tau: Vec<f64> = Vec::with_capacity(times.len() + 2);
    let mut kf: Vec<Option<usize>> = Vec::with_capacity(times.len() + 2);
    if m_kf == 1 {
        let h = times[1] - times[0];
        tau.extend([
            times[0],
            times[0] + h / 3.0,
            times[0] + 2.0 * h / 3.0,
            times[1],
        ]);
        kf.extend([Some(0), None, None, Some(1)]);
    } else {
        tau.push(times[0]);
        kf.push(Some(0));
        tau.push(0.5 * (times[0] + times[1]));
        kf.push(None);
        for (k, &t) in times.iter().enumerate().take(m_kf).skip(1) {
            tau.push(t);
            kf.push(Some(k));
        }
        tau.push(0.5 * (times[m_kf - 1] + times[m_kf]));
        kf.push(None);
        tau.push(times[m_kf]);
        kf.push(Some(m_kf));
    }
    (tau, kf)
}

/// Coefficient of `q_i` in the right-hand side of the row for knot `k`.
fn cubic_coef(h: &[f64], k: usize, i: usize) -> f64 {
    if i + 1 == k {
        6.0 / h[k - 1]
    } else if i == k {
        -6.0 * (1.0 / h[k] + 1.0 / h[k - 1])
    } else if i == k + 1 {
        6.0 / h[k]
    } else {
        0.0
    }
}

/// The tridiagonal matrix `[sub, diag, sup]` for knot intervals `h`, with
/// the extra knots' `M`-dependent parts (`s0 * M_1`, `sm * M_{m-1}`) moved
/// to the left-hand side.
fn cubic_matrix(h: &[f64], s0: f64, sm: f64) -> [Vec<f64>; 3] {
    let m = h.len();
    let n = m - 1;
    let mut sub = vec![0.0; n];
    let mut diag = vec![0.0; n];
    let mut sup = vec![0.0; n];
    for r in 0..n {
        let k = r + 1;
        sub[r] = h[k - 1];
        diag[r] = 2.0 * (h[k - 1] + h[k]);
        sup[r] = h[k];
    }
    let last_extra = m - 1;
    for (i, s) in [(FIRST_EXTRA, s0), (last_extra, sm)] {
        for k in i.saturating_sub(1).max(1)..=(i + 1).min(m - 1) {
            let c = cubic_coef(h, k, i) * s;
            let r = k - 1;
            let col = i - 1; // unknown index of M_i
            if col + 1 == r {
                sub[r] -= c;
            } else if col == r {
                diag[r] -= c;
            } else if col == r + 1 {
                sup[r] -= c;
            }
        }
    }
    [sub, diag, sup]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_run(shape: TimedShape, times: &[f64], pos: &[&[f64]]) -> Vec<Piece> {
        let mut out = vec![Vec::new()];
        run(shape, times, pos, &mut out);
        let ps = out.pop().unwrap_or_default();
        // Passes every keyframe at its time, continuous v and a, rest at ends.
        for (k, &t) in times.iter().enumerate() {
            let p = ps
                .iter()
                .find(|p| p.t0 <= t && t <= p.t1)
                .map(|p| p.eval(t).0);
            assert!(
                (p.unwrap_or(f64::NAN) - pos[k][0]).abs() < 1e-9,
                "{shape:?} kf {k}"
            );
        }
        for w in ps.windows(2) {
            let (a, b) = (w[0].eval(w[0].t1), w[1].eval(w[1].t0));
            assert!(
                (a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-9 && (a.2 - b.2).abs() < 1e-9
            );
        }
        let (first, last) = (
            ps[0].eval(ps[0].t0),
            ps[ps.len() - 1].eval(ps[ps.len() - 1].t1),
        );
        assert!(first.1.abs() < 1e-9 && first.2.abs() < 1e-9);
        assert!(
            last.1.abs() < 1e-9 && last.2.abs() < 1e-9,
            "{shape:?} {last:?}"
        );
        ps
    }

    #[test]
    fn all_shapes_interpolate_with_rest_ends() {
        let times = [0.0, 1.0, 1.5, 3.0, 3.2];
        let pos: [&[f64]; 5] = [&[0.0], &[1.0], &[2.0], &[-1.0], &[-0.5]];
        for shape in [
            TimedShape::Cubic,
            TimedShape::Monotone,
            TimedShape::MinimumJerk,
        ] {
            check_run(shape, &times, &pos);
            check_run(shape, &times[..2], &pos[..2]);
            check_run(shape, &times[..3], &pos[..3]);
        }
    }

    #[test]
    fn monotone_never_overshoots() {
        let times = [0.0, 0.2, 1.5, 1.6, 3.0];
        let pos: [&[f64]; 5] = [&[0.0], &[1.0], &[1.1], &[3.0], &[3.0]];
        let ps = check_run(TimedShape::Monotone, &times, &pos);
        for (k, p) in ps.iter().enumerate() {
            let (lo, hi) = p.range(0);
            let (a, b) = (pos[k][0].min(pos[k + 1][0]), pos[k][0].max(pos[k + 1][0]));
            assert!(lo >= a - 1e-12 && hi <= b + 1e-12, "segment {k}: {lo} {hi}");
        }
    }
}
