//! One polynomial piece of a joint's path, and the root finding used to
//! compute exact peaks of such pieces.

use crate::profile::SIXTH;

/// A polynomial of degree at most five on `[t0, t1]`, in the local time
/// `x = t - t0`: `p(x) = c0 + c1 x + c2 x^2 + c3 x^3 + c4 x^4 + c5 x^5`.
///
/// Every path the planner builds (constant-jerk phases, cubic splines,
/// quintic segments) is a sequence of these, so sampling has one code path.
/// Invariant: `t1 >= t0` and every coefficient is finite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Piece {
    pub t0: f64,
    pub t1: f64,
    pub c: [f64; 6],
}

impl Piece {
    /// A constant-jerk phase starting from position `p`, velocity `v`,
    /// acceleration `a`.
    pub fn jerk(t0: f64, dt: f64, p: f64, v: f64, a: f64, j: f64) -> Self {
        Piece {
            t0,
            t1: t0 + dt,
            c: [p, v, 0.5 * a, j * SIXTH, 0.0, 0.0],
        }
    }

    /// A piece holding position `p` at rest.
    pub fn hold(t0: f64, t1: f64, p: f64) -> Self {
        Piece {
            t0,
            t1,
            c: [p, 0.0, 0.0, 0.0, 0.0, 0.0],
        }
    }

    /// Duration of the piece.
    #[inline]
    pub fn duration(&self) -> f64 {
        self.t1 - self.t0
    }

    /// Position, velocity and acceleration at local time `x` (not clamped).
    /// Estrin's scheme: short dependency chains, so the evaluations of
    /// several joints overlap in the CPU.
    #[inline(always)]
    pub fn eval_local(&self, x: f64) -> (f64, f64, f64) {
        let c = &self.c;
        if c[4] == 0.0 && c[5] == 0.0 {
            // Constant-jerk phases and cubic splines: most pieces.
            let p = c[0] + x * (c[1] + x * (c[2] + x * c[3]));
            let v = c[1] + x * (2.0 * c[2] + x * (3.0 * c[3]));
            let a = 2.0 * c[2] + x * (6.0 * c[3]);
            return (p, v, a);
        }
        let x2 = x * x;
        let x4 = x2 * x2;
        let p = (c[0] + c[1] * x) + x2 * (c[2] + c[3] * x) + x4 * (c[4] + c[5] * x);
        let v = (c[1] + 2.0 * c[2] * x) + x2 * (3.0 * c[3] + 4.0 * c[4] * x) + x4 * (5.0 * c[5]);
        let a = (2.0 * c[2] + 6.0 * c[3] * x) + x2 * (12.0 * c[4] + 20.0 * c[5] * x);
        (p, v, a)
    }

    /// Position, velocity and acceleration at absolute time `t`, clamped to
    /// the piece.
    #[inline(always)]
    pub fn eval(&self, t: f64) -> (f64, f64, f64) {
        let x = (t - self.t0).clamp(0.0, self.t1 - self.t0);
        self.eval_local(x)
    }

    /// Coefficients of the `k`-th derivative (k <= 3), low order first.
    fn derivative(&self, k: usize) -> [f64; 6] {
        let mut d = self.c;
        for _ in 0..k {
            let mut n = [0.0; 6];
            for (i, slot) in n.iter_mut().enumerate().take(5) {
                *slot = d[i + 1] * (i + 1) as f64;
            }
            d = n;
        }
        d
    }

    /// Minimum and maximum of the `k`-th derivative over the piece.
    pub fn range(&self, k: usize) -> (f64, f64) {
        let d = self.derivative(k);
        poly_range(&d, self.duration())
    }

    /// Largest absolute value of the `k`-th derivative over the piece.
    pub fn peak(&self, k: usize) -> f64 {
        let (lo, hi) = self.range(k);
        lo.abs().max(hi.abs())
    }

    /// The coefficients of this polynomial about absolute time `t`:
    /// `q(y) = p(t + y)` (a Taylor shift, by Horner's scheme).
    pub fn about(&self, t: f64) -> [f64; 6] {
        let x0 = t - self.t0;
        let mut c = self.c;
        if x0 != 0.0 {
            for i in 0..5 {
                for k in (i..5).rev() {
                    c[k] += x0 * c[k + 1];
                }
            }
        }
        c
    }

    /// The same polynomial on `[t0, t1]` (a part of the piece, or beyond
    /// it).
    pub fn part(&self, t0: f64, t1: f64) -> Piece {
        Piece {
            t0,
            t1,
            c: self.about(t0),
        }
    }

    /// The piece with time reversed about `end / 2`: `q(s) = p(end - s)`,
    /// on `[end - t1, end - t0]`.
    pub fn mirrored(&self, end: f64) -> Piece {
        let mut c = self.about(self.t1);
        for (k, ck) in c.iter_mut().enumerate() {
            if k % 2 == 1 {
                *ck = -*ck;
            }
        }
        Piece {
            t0: end - self.t1,
            t1: end - self.t0,
            c,
        }
    }

    /// The same piece with time stretched by `s` around `origin`:
    /// `q(t) = p(origin + (t - origin) / s)`.
    pub fn stretched(&self, origin: f64, s: f64) -> Self {
        let mut c = self.c;
        let mut f = 1.0;
        for ck in c.iter_mut() {
            *ck *= f;
            f /= s;
        }
        Piece {
            t0: origin + (self.t0 - origin) * s,
            t1: origin + (self.t1 - origin) * s,
            c,
        }
    }
}

/// Evaluates a polynomial (low order first).
fn poly(c: &[f64; 6], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ck| acc * x + ck)
}

fn degree(c: &[f64; 6]) -> usize {
    (0..6).rev().find(|&i| c[i] != 0.0).unwrap_or(0)
}

/// Minimum and maximum of a polynomial over `[0, len]`: the extremes are at
/// the ends or at real roots of the derivative inside.
pub(crate) fn poly_range(c: &[f64; 6], len: f64) -> (f64, f64) {
    let mut lo = c[0].min(poly(c, len));
    let mut hi = c[0].max(poly(c, len));
    let mut d = [0.0; 6];
    for i in 0..5 {
        d[i] = c[i + 1] * (i + 1) as f64;
    }
    let mut roots = [0.0; 5];
    let n = roots_in(&d, len, &mut roots);
    for &r in &roots[..n] {
        let y = poly(c, r);
        lo = lo.min(y);
        hi = hi.max(y);
    }
    (lo, hi)
}

/// Real roots of a polynomial of degree <= 4 strictly inside `(0, len)`,
/// written to `out`; returns how many. Roots are isolated between the
/// critical points (found recursively), so every sign change is bracketed
/// and refined by bisection: slow but robust, used only off the hot path.
fn roots_in(c: &[f64; 6], len: f64, out: &mut [f64; 5]) -> usize {
    let deg = degree(c);
    match deg {
        0 => 0,
        1 => {
            let r = -c[0] / c[1];
            push_if_inside(r, len, out, 0)
        }
        2 => {
            let (a, b, cc) = (c[2], c[1], c[0]);
            let disc = b * b - 4.0 * a * cc;
            if disc < 0.0 {
                return 0;
            }
            let sq = disc.sqrt();
            // Numerically stable pair of roots.
            let q = -0.5 * (b + b.signum() * sq);
            let mut n = 0;
            if q != 0.0 {
                n = push_if_inside(cc / q, len, out, n);
                n = push_if_inside(q / a, len, out, n);
            } else {
                n = push_if_inside(0.0, len, out, n);
            }
            n
        }
        _ => {
            let mut d = [0.0; 6];
            for i in 0..5 {
                d[i] = c[i + 1] * (i + 1) as f64;
            }
            let mut crit = [0.0; 5];
            let nc = roots_in(&d, len, &mut crit);
            crit[..nc].sort_by(f64::total_cmp);
            let mut n = 0;
            let mut a = 0.0;
            for b in crit[..nc].iter().copied().chain(core::iter::once(len)) {
                n = bisect_root(c, a, b, len, out, n);
                a = b;
            }
            n
        }
    }
}

fn push_if_inside(r: f64, len: f64, out: &mut [f64; 5], n: usize) -> usize {
    if r.is_finite() && r > 0.0 && r < len && n < out.len() {
        out[n] = r;
        n + 1
    } else {
        n
    }
}

fn bisect_root(
    c: &[f64; 6],
    mut a: f64,
    mut b: f64,
    len: f64,
    out: &mut [f64; 5],
    n: usize,
) -> usize {
    let fa = poly(c, a);
    let fb = poly(c, b);
    if fa == 0.0 {
        return push_if_inside(a, len, out, n);
    }
    if fa.signum() == fb.signum() {
        return n;
    }
    for _ in 0..100 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        let fm = poly(c, m);
        if fm.signum() == fa.signum() {
            a = m;
        } else {
            b = m;
        }
    }
    push_if_inside(0.5 * (a + b), len, out, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_of_quintic_matches_dense_scan() {
        let p = Piece {
            t0: 0.0,
            t1: 2.0,
            c: [0.3, -1.0, 0.5, 2.0, -1.7, 0.4],
        };
        for k in 0..3 {
            let (lo, hi) = p.range(k);
            let d = p.derivative(k);
            let (mut slo, mut shi) = (f64::MAX, f64::MIN);
            for i in 0..=20000 {
                let y = poly(&d, 2.0 * i as f64 / 20000.0);
                slo = slo.min(y);
                shi = shi.max(y);
            }
            assert!((lo - slo).abs() < 1e-6 && (hi - shi).abs() < 1e-6, "k={k}");
        }
    }

    #[test]
    fn shifted_and_mirrored_pieces_are_the_same_polynomial() {
        let p = Piece {
            t0: 0.5,
            t1: 1.5,
            c: [0.3, -1.0, 0.5, 2.0, -1.7, 0.4],
        };
        let part = p.part(0.8, 1.2);
        let mirrored = p.mirrored(3.0);
        for i in 0..=10 {
            let t = 0.8 + 0.04 * i as f64;
            let (a, b) = (p.eval_local(t - p.t0), part.eval_local(t - part.t0));
            assert!((a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12);
            assert!((a.2 - b.2).abs() < 1e-12);
            // Reversed time: the same position, the opposite velocity.
            let m = mirrored.eval_local(3.0 - t - mirrored.t0);
            assert!((a.0 - m.0).abs() < 1e-12 && (a.1 + m.1).abs() < 1e-12);
            assert!((a.2 - m.2).abs() < 1e-12);
        }
    }

    #[test]
    fn stretching_scales_derivatives() {
        let p = Piece::jerk(1.0, 2.0, 0.5, 1.0, 2.0, 3.0);
        let s = p.stretched(1.0, 2.0);
        let (p0, v0, a0) = p.eval(2.0);
        let (p1, v1, a1) = s.eval(3.0);
        assert!((p0 - p1).abs() < 1e-12);
        assert!((v0 / 2.0 - v1).abs() < 1e-12);
        assert!((a0 / 4.0 - a1).abs() < 1e-12);
    }
}
