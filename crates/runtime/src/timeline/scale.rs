//! The smooth time scale of the main path (pause and resume), and how
//! long its ramps take.

use servobus_trajectory::JointLimits;

/// Smooth time scale of the main path: `s` ramps from `s0` to `s1` over
/// `dur` seconds from `r0` with a quintic smoothstep (continuous `s`, `s'`
/// and `s''`), and path time `tau` is its integral.
#[derive(Debug, Clone, Copy)]
pub(super) struct Scale {
    r0: f64,
    tau0: f64,
    s0: f64,
    s1: f64,
    dur: f64,
}

impl Scale {
    pub fn constant(r0: f64) -> Self {
        Scale {
            r0,
            tau0: 0.0,
            s0: 1.0,
            s1: 1.0,
            dur: 1.0,
        }
    }

    /// `(tau, s, ds/dx)` at time `x`.
    pub fn at(&self, x: f64) -> (f64, f64, f64) {
        let dx = x - self.r0;
        if dx <= 0.0 {
            // Before the ramp (the reference lags the commands by the lead):
            // extrapolate at the starting speed.
            return (self.tau0 + self.s0 * dx, self.s0, 0.0);
        }
        let u = dx / self.dur;
        let d = self.s1 - self.s0;
        if u >= 1.0 {
            let tau = self.tau0 + self.s0 * dx + d * (0.5 * self.dur + (dx - self.dur));
            return (tau, self.s1, 0.0);
        }
        let h = u * u * u * (10.0 + u * (-15.0 + 6.0 * u));
        let dh = 30.0 * u * u * (1.0 - u) * (1.0 - u);
        let big_h = u * u * u * u * (2.5 + u * (-3.0 + u));
        (
            self.tau0 + self.s0 * dx + d * self.dur * big_h,
            self.s0 + d * h,
            d * dh / self.dur,
        )
    }

    /// A ramp from the scale at `x` to `target` over `dur`.
    pub fn ramp_to(&self, x: f64, target: f64, dur: f64) -> Scale {
        let (tau, s, _) = self.at(x);
        Scale {
            r0: x,
            tau0: tau,
            s0: s,
            s1: target,
            dur: dur.max(1e-3),
        }
    }
}

/// The shortest pause or resume ramp, s (joints with a high acceleration
/// for their speed still change speed over a few cycles, not one).
const MIN_PAUSE_RAMP: f64 = 0.05;

/// The longest pause or resume ramp, s (a slow joint does not make a
/// pause take longer than this).
const MAX_PAUSE_RAMP: f64 = 3.0;

/// How long pausing or resuming ramps the path's time scale, s: the
/// longest the limits allow without asking more than about half of a
/// joint's acceleration for the slow-down itself (the quintic ramp's
/// peak slope is 1.875 / duration, so a ramp of `3.75 v / a` slows a joint
/// at speed `v` by at most `a / 2`), between [`MIN_PAUSE_RAMP`] and
/// [`MAX_PAUSE_RAMP`].
pub(super) fn pause_ramp(limits: &[JointLimits]) -> f64 {
    limits
        .iter()
        .map(|l| 3.75 * l.max_velocity / l.max_acceleration)
        .fold(MIN_PAUSE_RAMP, f64::max)
        .min(MAX_PAUSE_RAMP)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_time_scale_integrates_its_ramp() {
        let s = Scale::constant(1.0).ramp_to(2.0, 0.0, 0.5);
        assert_eq!(s.at(2.0), (1.0, 1.0, 0.0));
        let (tau, v, dv) = s.at(2.25);
        assert!((v - 0.5).abs() < 1e-12 && dv < 0.0);
        // Midway through a symmetric ramp the integral is 0.25 * (1 + 0.5) - ...
        assert!(tau > 1.125 && tau < 1.25, "{tau}");
        let (tau_end, v_end, _) = s.at(3.0);
        assert_eq!(v_end, 0.0);
        assert!((tau_end - 1.25).abs() < 1e-12, "{tau_end}");
    }
}
