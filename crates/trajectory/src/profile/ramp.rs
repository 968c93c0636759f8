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
    /// The shortest ramp changing the speed by `dv` under `a` and `j`
    /// (`j` may be infinite).
    #[inline]
    pub fn new(dv: f64, a: f64, j: f64) -> Ramp {
        Ramp::of(dv, &Acc::new(a, j))
    }

    /// [`new`](Self::new) with the bounds' constants made once (see
    /// [`Acc`]): no division.
    #[inline]
    pub(super) fn of(dv: f64, c: &Acc) -> Ramp {
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

/// Acceleration and jerk bounds with the reciprocals the solvers need,
/// computed once per call instead of dividing in every iteration.
#[derive(Debug, Clone, Copy)]
pub(super) struct Acc {
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
    #[inline]
    pub fn new(a: f64, j: f64) -> Self {
        // Two divisions, the rest by multiplying (a division costs as
        // much as several multiplications, and these are made per call).
        let inv_j = 1.0 / j;
        let k = a * inv_j;
        Acc {
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
pub(crate) fn rest_peak(dist: f64, lim: &JointLimits) -> f64 {
    let (vm, a, j) = (lim.max_velocity, lim.max_acceleration, lim.jerk());
    if dist <= 0.0 {
        return 0.0;
    }
    if dist >= vm * Ramp::new(vm, a, j).duration() {
        return vm;
    }
    // Constant-acceleration regime: vc (vc / a + a / j) = dist.
    let k = a / j;
    let vc = 0.5 * a * (-k + (k * k + 4.0 * dist / a).sqrt());
    if vc * j >= a * a {
        return vc.min(vm);
    }
    // Pure jerk regime: dist = 2 vc sqrt(vc / j).
    (0.25 * dist * dist * j).cbrt().min(vm)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rest_peak_matches_definition() {
        let l = JointLimits::new(2.0, 3.0, Some(10.0));
        for &d in &[0.01, 0.1, 0.5, 1.0, 3.0, 10.0] {
            let vc = rest_peak(d, &l);
            let r = Ramp::new(vc, 3.0, 10.0);
            let dist = vc * r.duration();
            assert!(vc <= 2.0 + 1e-12);
            assert!(
                vc == 2.0 || (dist - d).abs() < 1e-9 * d,
                "d={d} vc={vc} dist={dist}"
            );
        }
    }
}
