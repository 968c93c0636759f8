//! Velocity ramps: the S-curve speed changes at both ends of a segment, and
//! the closed forms built on them alone.

use crate::JointLimits;

/// A velocity ramp of size `dv >= 0`: jerk phases of `tj`, a constant
/// acceleration phase of `ta`, reaching acceleration `peak`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Ramp {
    pub tj: f64,
    pub ta: f64,
    pub peak: f64,
}

impl Ramp {
    /// The shortest ramp changing the speed by `dv` within the bounds `c`
    /// (made once, see [`Acc`]: no division).
    #[inline]
    pub(crate) fn of(dv: f64, c: &Acc) -> Ramp {
        if dv <= 0.0 {
            Ramp {
                tj: 0.0,
                ta: 0.0,
                peak: 0.0,
            }
        } else if dv >= c.regime {
            Ramp {
                tj: c.k,
                ta: dv * c.inv_a - c.k,
                peak: c.a,
            }
        } else {
            let tj = (dv * c.inv_j).sqrt();
            Ramp {
                tj,
                ta: 0.0,
                peak: c.j * tj,
            }
        }
    }

    #[inline]
    pub fn duration(&self) -> f64 {
        2.0 * self.tj + self.ta
    }
}

/// A joint's speed, acceleration and jerk bounds with the reciprocals the
/// solvers need, computed once (two divisions) and handed down instead of
/// dividing in every function and every iteration.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Acc {
    /// The speed limit.
    pub vm: f64,
    /// Whether the jerk is limited (`j` finite).
    pub finite: bool,
    /// The acceleration limit.
    pub a: f64,
    pub inv_a: f64,
    pub j: f64,
    /// `1 / j` (0 without a jerk limit).
    pub inv_j: f64,
    /// `a / j`: duration of a full jerk phase (0 without a jerk limit).
    pub k: f64,
    /// `a^2 / j`: the speed change above which a ramp has a constant
    /// acceleration phase.
    pub regime: f64,
}

impl Acc {
    /// The bounds of `lim`.
    #[inline]
    pub fn of(lim: &JointLimits) -> Self {
        let (a, j) = (lim.max_acceleration, lim.jerk());
        // Two divisions, the rest by multiplying (a division costs as
        // much as several multiplications).
        let inv_j = 1.0 / j;
        let k = a * inv_j;
        Acc {
            vm: lim.max_velocity,
            finite: lim.max_jerk.is_some(),
            a,
            inv_a: 1.0 / a,
            j,
            inv_j,
            k,
            regime: a * k,
        }
    }
}

/// Duration and distance of the ramp from `u` to `w` and their derivatives
/// with respect to `w`. Distance is `(u + w) / 2 * duration` because an
/// S-curve ramp is point-symmetric about its midpoint.
#[inline(always)]
pub(super) fn leg(u: f64, w: f64, c: &Acc) -> (f64, f64, f64, f64) {
    let dv = (w - u).abs();
    let sgn = if w >= u { 1.0 } else { -1.0 };
    let (dur, ddur) = if dv >= c.regime {
        (dv * c.inv_a + c.k, c.inv_a)
    } else if dv > 0.0 {
        // `s = sqrt(dv j)`: jerk phases of `s / j` each, and
        // `d(2 sqrt(dv / j)) / d dv = 1 / s`.
        let s = (dv * c.j).sqrt();
        (2.0 * s * c.inv_j, 1.0 / s)
    } else {
        (0.0, f64::INFINITY)
    };
    let ddur_dw = sgn * ddur;
    let dist = 0.5 * (u + w) * dur;
    let ddist = 0.5 * dur + 0.5 * (u + w) * ddur_dw;
    (dur, dist, ddur_dw, ddist)
}

/// Largest `vc` with `vc * ramp_duration(vc) <= dist`: the peak speed of a
/// rest-to-rest move of `dist` (closed form).
#[inline]
pub(crate) fn rest_peak(dist: f64, c: &Acc) -> f64 {
    let (vm, a, k) = (c.vm, c.a, c.k);
    if dist <= 0.0 {
        return 0.0;
    }
    if let Some((vc, _)) = rest_short(dist, c) {
        return vc;
    }
    if dist >= vm * Ramp::of(vm, c).duration() {
        return vm;
    }
    // Constant-acceleration regime (the distance is beyond the pure jerk
    // one's): vc (vc / a + a / j) = dist.
    (0.5 * a * (-k + (k * k + 4.0 * dist * c.inv_a).sqrt())).min(vm)
}

/// The peak speed and duration of the rest-to-rest move of `dist > 0`
/// when its ramps are pure jerk and the speed limit does not cap it, else
/// `None`. Pure jerk ramps hold while the peak is at most `regime = a k`,
/// whose ramp takes `2 k`: distances up to `2 regime k` (short moves, the
/// follower's usual case). Each ramp is two jerk phases of `tj`, covering
/// `dist / 2 = j tj^3`: the peak is `j tj^2` and the move lasts `4 tj`,
/// one cube root and no square root or division.
#[inline]
pub(super) fn rest_short(dist: f64, c: &Acc) -> Option<(f64, f64)> {
    if !(dist > 0.0 && dist <= 2.0 * c.regime * c.k) {
        return None;
    }
    let tj = cube_root(0.5 * dist * c.inv_j);
    let vc = c.j * tj * tj;
    (vc <= c.vm).then_some((vc, 4.0 * tj))
}

/// The cube root of `x` to within 1e-14 relative, faster than `f64::cbrt`
/// (correctly rounded, which nothing here needs; its chain of dependent
/// operations is what a follower's cycle waits for): [`halley_cbrt`] with
/// two steps.
#[inline]
pub(crate) fn cube_root(x: f64) -> f64 {
    halley_cbrt(x, 2)
}

/// The cube root of `x` to within 1e-4 relative (one Halley step): a
/// starting guess for a search.
#[inline]
pub(crate) fn cube_root_rough(x: f64) -> f64 {
    halley_cbrt(x, 1)
}

/// The cube root of `x`: the exponent divided by 3 in the bits for a
/// first guess within a few percent, then `steps` Halley steps (cubic
/// convergence: to some 1e-4, then 1e-14). Values that are not positive
/// normal numbers go to `f64::cbrt`.
#[inline(always)]
fn halley_cbrt(x: f64, steps: usize) -> f64 {
    if !(f64::MIN_POSITIVE..f64::INFINITY).contains(&x) {
        return x.cbrt();
    }
    // Bits of a normal `x` are about `2^52 (e + 1023)`: a third of them
    // plus `2^52 * 2 * 1023 / 3`, less a little for the mantissa's
    // curvature, is about `2^52 (e / 3 + 1023)`.
    let mut y = f64::from_bits(x.to_bits() / 3 + 0x2A9F_7893_782D_A1CE);
    for _ in 0..steps {
        let y3 = y * y * y;
        y *= (y3 + 2.0 * x) / (2.0 * y3 + x);
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cube_roots_are_within_their_tolerance() {
        // Exact cubes first, then a sweep over 600 orders of magnitude.
        for (x, r) in [
            (8.0, 2.0),
            (27.0, 3.0),
            (0.125, 0.5),
            (1e-9, 1e-3),
            (1e30, 1e10),
        ] {
            assert!((cube_root(x) - r).abs() <= 1e-14 * r, "{x}");
            assert!((cube_root_rough(x) - r).abs() <= 1e-4 * r, "{x}");
        }
        let mut x = 1e-300;
        while x < 1e300 {
            let r = cube_root(x);
            assert!(((r * r * r) / x - 1.0).abs() < 3e-14, "{x}: {r}");
            let r = cube_root_rough(x);
            assert!(((r * r * r) / x - 1.0).abs() < 3e-4, "{x}: {r}");
            x *= 1.37;
        }
        assert_eq!(cube_root(0.0), 0.0);
        assert!(cube_root(f64::NAN).is_nan());
        assert_eq!(cube_root(-8.0), -2.0);
        assert_eq!(cube_root(f64::INFINITY), f64::INFINITY);
    }

    #[test]
    fn rest_peak_matches_definition() {
        let l = JointLimits::new(2.0, 3.0, Some(10.0));
        for &d in &[0.01, 0.1, 0.5, 1.0, 3.0, 10.0] {
            let vc = rest_peak(d, &Acc::of(&l));
            let r = Ramp::of(vc, &Acc::of(&l));
            let dist = vc * r.duration();
            assert!(vc <= 2.0 + 1e-12);
            assert!(
                vc == 2.0 || (dist - d).abs() < 1e-9 * d,
                "d={d} vc={vc} dist={dist}"
            );
        }
    }
}
