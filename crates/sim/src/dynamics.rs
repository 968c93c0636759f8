//! The physics of one joint: a motion profile (trapezoid of speed and
//! acceleration), a first-order lag, a dead zone, an external load, a
//! mechanical block and the thermal and electrical figures that follow.
//!
//! Everything is in the servo's sensor frame (ticks, before the homing
//! offset) and in seconds. The model is deterministic: it depends only on
//! the inputs and the time steps it is given.

use crate::body::turn_delta;

/// Thermal time constant of the motor and case.
const THERMAL_TAU_S: f64 = 120.0;
/// Steady temperature rise above ambient at full effort.
const FULL_EFFORT_RISE_C: f64 = 50.0;
/// Speed at which an unpowered joint sags under a full load (ticks/s).
const SAG_SPEED: f64 = 400.0;
/// Longest integration step; longer spans are cut into steps of this size.
pub(crate) const MAX_STEP_S: f64 = 0.001;

/// What the registers ask of the joint during one step.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Drive {
    /// Torque enabled (register 40).
    pub torque_on: bool,
    /// Operating mode 1: constant speed (wheel) instead of position.
    pub wheel: bool,
    /// Time constant of the first-order lag between the motion profile and
    /// the shaft, s: the model's response lag (the protocol crate's fact).
    pub lag_s: f64,
    /// Target position in sensor ticks (position mode).
    pub target: f64,
    /// Signed speed in wheel mode, ticks/s.
    pub wheel_speed: f64,
    /// Top speed of the profile, ticks/s (> 0).
    pub max_speed: f64,
    /// Profile acceleration, ticks/s^2 (infinite: no limit).
    pub accel: f64,
    /// Dead zone, ticks.
    pub dead_zone: f64,
    /// Torque available, as a fraction of the maximum (0..=1).
    pub torque_limit: f64,
    /// Ticks of position error that produce full effort (from the P gain).
    pub full_effort_error: f64,
    /// External torque as a fraction of the maximum; positive pushes
    /// towards lower ticks (as gravity on a raised arm).
    pub load: f64,
    /// The shaft cannot move.
    pub blocked: bool,
    /// Highest sensor position (resolution - 1).
    pub max_pos: f64,
    /// The shaft turns freely past the sensor's seam (a mounted joint on a
    /// full-turn sensor): positions wrap instead of stopping at the ends.
    pub seamless: bool,
    /// Ambient temperature, C.
    pub ambient_c: f64,
}

/// The state of the joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Joint {
    /// Shaft position, sensor ticks.
    pub pos: f64,
    /// Shaft speed, ticks/s.
    pub vel: f64,
    /// Profile reference position.
    pub ref_pos: f64,
    /// Profile reference speed.
    pub ref_vel: f64,
    /// Fraction of maximum torque the motor produces (signed).
    pub effort: f64,
    /// Motor temperature, C.
    pub temp_c: f64,
    /// Seconds spent unable to reach the reference at the torque limit.
    pub stalled_s: f64,
}

impl Joint {
    pub(crate) fn at(pos: f64, temp_c: f64) -> Joint {
        Joint {
            pos,
            vel: 0.0,
            ref_pos: pos,
            ref_vel: 0.0,
            effort: 0.0,
            temp_c,
            stalled_s: 0.0,
        }
    }

    /// Whether nothing will change but the temperature: the profile has
    /// arrived and the shaft rests.
    pub(crate) fn quiescent(&self, d: &Drive) -> bool {
        if d.wheel && d.torque_on && d.wheel_speed != 0.0 {
            return false;
        }
        let pushed = d.load != 0.0 && (!d.torque_on || d.load.abs() > d.torque_limit);
        !pushed
            && self.vel == 0.0
            && self.ref_vel == 0.0
            && (!d.torque_on || d.wheel || self.ref_pos == d.target)
            && self.stalled_s == 0.0
    }

    /// Advances the profile reference by `dt` towards the target.
    fn profile(&mut self, d: &Drive, dt: f64) {
        if d.wheel {
            self.ref_vel = approach(self.ref_vel, d.wheel_speed, d.accel * dt);
            self.ref_pos += self.ref_vel * dt;
            return;
        }
        let dist = d.target - self.ref_pos;
        if dist == 0.0 && self.ref_vel == 0.0 {
            return;
        }
        // The fastest speed from which the profile can still stop at the
        // target with its acceleration: the trapezoid's braking branch.
        let v_stop = if d.accel.is_finite() {
            (2.0 * d.accel * dist.abs()).sqrt()
        } else {
            f64::INFINITY
        };
        let v_des = dist.signum() * d.max_speed.min(v_stop);
        self.ref_vel = approach(self.ref_vel, v_des, d.accel * dt);
        let step = self.ref_vel * dt;
        if step.abs() >= dist.abs() && step.signum() == dist.signum() || dist.abs() < 1e-6 {
            self.ref_pos = d.target;
            self.ref_vel = 0.0;
        } else {
            self.ref_pos += step;
        }
    }

    /// One integration step of `dt` seconds (any length: large steps stay
    /// stable because the lag is integrated exactly).
    pub(crate) fn step(&mut self, d: &Drive, dt: f64) {
        if dt <= 0.0 {
            return;
        }
        let before = self.pos;
        if d.torque_on {
            self.profile(d, dt);
            if d.wheel {
                self.ref_pos = self.ref_pos.rem_euclid(d.max_pos + 1.0);
            }
            let error = self.ref_pos - self.pos;
            let demand = d.load + error / d.full_effort_error;
            let limit = d.torque_limit;
            self.effort = demand.clamp(-limit, limit);
            // The load overpowers the motor unless the motor drives the way
            // the load pushes (a positive load pushes towards lower ticks):
            // then both move the shaft, as a gripper backs out of an object
            // squeezed at its torque limit.
            let with_load = error * d.load < 0.0;
            let overpowered = d.load.abs() > limit && !with_load;
            if d.blocked {
                self.vel = 0.0;
            } else if overpowered {
                // The load wins: the shaft is pushed back against the motor.
                let excess = d.load.abs() - limit;
                self.pos -= d.load.signum() * excess * SAG_SPEED * dt;
            } else if d.wheel {
                self.pos = self.ref_pos;
            } else {
                // The shaft settles where the motor's effort balances the
                // load: the profile minus the sag the load causes.
                let eq = self.ref_pos - d.load * d.full_effort_error;
                let err = eq - self.pos;
                let settled = self.ref_pos == d.target;
                if !(settled && err.abs() <= d.dead_zone.max(0.5)) {
                    self.pos += err * (1.0 - (-dt / d.lag_s).exp());
                }
            }
            let saturated = demand.abs() > limit && (d.blocked || overpowered);
            if saturated {
                self.stalled_s += dt;
            } else {
                self.stalled_s = 0.0;
            }
        } else {
            self.ref_vel = 0.0;
            self.effort = 0.0;
            self.stalled_s = 0.0;
            if !d.blocked && d.load != 0.0 {
                self.pos -= d.load * SAG_SPEED * dt;
            }
            self.ref_pos = self.pos;
        }
        let turn = d.max_pos + 1.0;
        if !d.wheel && !d.seamless {
            self.pos = self.pos.clamp(0.0, d.max_pos);
        } else {
            self.pos = self.pos.rem_euclid(turn);
        }
        let moved = if d.seamless {
            // Across the seam the shortest way round is the way it went.
            turn_delta(self.pos, before, turn)
        } else {
            self.pos - before
        };
        self.vel = if d.wheel && d.torque_on && !d.blocked {
            self.ref_vel
        } else {
            moved / dt
        };
        if self.vel.abs() < 1e-9 {
            self.vel = 0.0;
        }
        // Heat: the steady rise grows with the square of the effort;
        // integrated exactly so that long steps are stable.
        let steady = d.ambient_c + FULL_EFFORT_RISE_C * self.effort * self.effort;
        self.temp_c = steady + (self.temp_c - steady) * (-dt / THERMAL_TAU_S).exp();
    }
}

/// Moves `from` towards `to` by at most `max_delta` (infinite: jump).
fn approach(from: f64, to: f64, max_delta: f64) -> f64 {
    if (to - from).abs() <= max_delta {
        to
    } else {
        from + (to - from).signum() * max_delta
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drive(target: f64) -> Drive {
        Drive {
            torque_on: true,
            wheel: false,
            lag_s: 0.010,
            target,
            wheel_speed: 0.0,
            max_speed: 1000.0,
            accel: 5000.0,
            dead_zone: 1.0,
            torque_limit: 1.0,
            full_effort_error: 50.0,
            load: 0.0,
            blocked: false,
            max_pos: 4095.0,
            seamless: false,
            ambient_c: 25.0,
        }
    }

    #[test]
    fn trapezoid_cruises_at_max_speed_and_arrives() {
        let d = drive(3000.0);
        let mut j = Joint::at(1000.0, 25.0);
        let mut peak: f64 = 0.0;
        for _ in 0..3000 {
            j.step(&d, 0.001);
            peak = peak.max(j.ref_vel);
        }
        assert_eq!(peak, 1000.0);
        assert_eq!(j.ref_pos, 3000.0);
        assert!((j.pos - 3000.0).abs() <= 1.0, "{}", j.pos);
    }

    #[test]
    fn torque_off_joint_sags_under_load_and_rests_without() {
        let mut d = drive(0.0);
        d.torque_on = false;
        let mut j = Joint::at(2000.0, 25.0);
        j.step(&d, 0.5);
        assert_eq!(j.pos, 2000.0);
        d.load = 0.5;
        j.step(&d, 0.1);
        assert!(j.pos < 2000.0);
    }

    #[test]
    fn a_load_beyond_the_torque_limit_wins_unless_the_motor_drives_its_way() {
        // The load (1.2 of a 1.0 limit) pushes towards lower ticks.
        let mut d = drive(2200.0);
        d.load = 1.2;
        let mut j = Joint::at(2000.0, 25.0);
        for _ in 0..200 {
            j.step(&d, 0.001);
        }
        assert!(j.pos < 2000.0, "pushed back: {}", j.pos);
        assert!(j.stalled_s > 0.19, "stalled {}", j.stalled_s);
        // Driving down with the load, the shaft goes where both push, at
        // once (not at the load's crawl).
        let mut d = drive(1500.0);
        d.load = 1.2;
        let mut j = Joint::at(2000.0, 25.0);
        for _ in 0..300 {
            j.step(&d, 0.001);
        }
        // The load alone would have crawled 0.2 * 400 ticks/s * 0.3 s = 24.
        assert!(j.pos < 1850.0, "{}", j.pos);
    }
}
