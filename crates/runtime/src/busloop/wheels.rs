//! Wheel joints (`mode: wheel`): a commanded speed that ramps toward the
//! wheel's target speed every cycle, written as goal speed (register
//! `goal_speed`, 46, sign-magnitude, steps/s) in a SYNC WRITE frame of
//! its own.
//!
//! - The target comes from the timeline (a live target's value, 0 under a
//!   played path, a stop, a pause, a hold or a live timeout); the
//!   commanded speed moves toward it within the wheel's `max_acceleration`
//!   and, when given, `max_jerk` (one step per cycle), so that stopping
//!   the run, pausing it or losing the stream of targets brings the wheel
//!   to rest within its limits rather than at once.
//! - The speed in rad/s becomes steps/s through the joint's mapping (its
//!   direction, `inverted` or calibrated, included), rounded to a step and
//!   kept in the register's range; the register's own encoding
//!   ([`Register::encode`]) sets the sign bit.
//! - The frame is encoded into a buffer allocated when the loop is built:
//!   a cycle allocates nothing. A bus without wheels sends no such frame.

use servobus_driver::{Bus, BusError, Transport};
use servobus_protocol::registers::{ByteOrder, Register};

use crate::config::{BusConfig, JointMap, Units};
use crate::error::PortGone;

/// Below this, rad/s, a commanded speed and acceleration count as rest.
const REST: f64 = 1e-9;

/// One wheel's commanded speed.
#[derive(Debug, Clone)]
pub(crate) struct WheelGoal {
    /// Index of the joint in the bus.
    pub bus_index: usize,
    /// Index in the robot's joint order.
    pub robot_index: usize,
    /// Steps per rad/s of joint speed, signed by the joint's direction.
    steps_per_rad: f64,
    max_velocity: f64,
    max_acceleration: f64,
    max_jerk: Option<f64>,
    /// The speed commanded this cycle, rad/s.
    pub speed: f64,
    /// Its rate of change in the last step, rad/s^2.
    accel: f64,
    /// The speed the wheel heads for, rad/s.
    pub target: f64,
    /// The largest |commanded speed| so far, rad/s.
    pub peak: f64,
    /// The steps/s last encoded.
    steps: i32,
}

impl WheelGoal {
    /// One step of `dt` s toward the target: within the acceleration limit
    /// and, with a jerk limit, along an acceleration that ramps at it and
    /// eases off so as to arrive at the target speed with none left (the
    /// last step lands on the target).
    fn step(&mut self, dt: f64) {
        let target = self.target.clamp(-self.max_velocity, self.max_velocity);
        let d = target - self.speed;
        let a_max = self.max_acceleration;
        let accel = match self.max_jerk {
            Some(j) if j.is_finite() && j > 0.0 && dt > 0.0 => {
                // The acceleration from which ramping to none at the jerk
                // limit, a step of `dt` at a time, covers exactly the
                // speed left: a^2 / 2j + a dt / 2 = |d|.
                let a = j * ((0.25 * dt * dt + 2.0 * d.abs() / j).sqrt() - 0.5 * dt);
                let wanted = (d.signum() * a).clamp(-a_max, a_max);
                let jump = j * dt;
                self.accel + (wanted - self.accel).clamp(-jump, jump)
            }
            _ if dt > 0.0 => (d / dt).clamp(-a_max, a_max),
            _ => 0.0,
        };
        let next = self.speed + accel * dt;
        if d != 0.0 && (target - next).signum() != d.signum() {
            // Arrived (or would pass it): the step ends on the target,
            // which is no further than the step allowed.
            self.accel = 0.0;
            self.speed = target;
        } else {
            self.accel = accel;
            self.speed = next;
        }
        self.peak = self.peak.max(self.speed.abs());
    }

    /// One step of `dt` s covering `share` (0..=1) of what is left to the
    /// target (clamped to the top speed): the whole of it at 1.
    fn toward(&mut self, share: f64, dt: f64) {
        let target = self.target.clamp(-self.max_velocity, self.max_velocity);
        let next = if share >= 1.0 {
            target
        } else {
            self.speed + share * (target - self.speed)
        };
        self.accel = (next - self.speed) / dt;
        self.speed = next;
        if self.speed == target {
            self.accel = 0.0;
        }
        self.peak = self.peak.max(self.speed.abs());
    }

    /// The commanded speed as steps/s in `reg`'s range.
    fn steps(&self, reg: &Register) -> i32 {
        let (lo, hi) = reg.range();
        let s = (self.speed * self.steps_per_rad).round();
        if s.is_nan() {
            return 0;
        }
        // The float-to-int cast saturates; the clamp keeps it encodable.
        (s as i32).clamp(lo, hi)
    }
}

/// The wheels of one bus and the SYNC WRITE block of their goal speeds.
#[derive(Debug)]
pub(crate) struct WheelWriter {
    reg: Option<&'static Register>,
    order: ByteOrder,
    ids: Vec<u8>,
    /// One block per wheel: allocated once.
    data: Vec<u8>,
    pub wheels: Vec<WheelGoal>,
    /// The control period, s: one ramp step each.
    dt: f64,
}

impl WheelWriter {
    /// The wheels among `config`'s joints (the first is robot joint
    /// `first_joint`; `units` the robot file's), their goal speeds in `reg`
    /// (`None` on a bus without wheels), stepped every `dt` s.
    pub fn new(
        config: &BusConfig,
        first_joint: usize,
        units: Units,
        reg: Option<&'static Register>,
        order: ByteOrder,
        dt: f64,
    ) -> Self {
        let wheels: Vec<WheelGoal> = config
            .joints
            .iter()
            .enumerate()
            .filter(|(_, j)| j.is_wheel())
            .map(|(i, j)| {
                let map = JointMap::new(j, units);
                WheelGoal {
                    bus_index: i,
                    robot_index: first_joint + i,
                    steps_per_rad: map.raw_ticks(1.0) - map.raw_ticks(0.0),
                    max_velocity: units.to_rad(j.max_velocity).abs(),
                    max_acceleration: units.to_rad(j.max_acceleration).abs(),
                    max_jerk: j.max_jerk.map(|x| units.to_rad(x).abs()),
                    speed: 0.0,
                    accel: 0.0,
                    target: 0.0,
                    peak: 0.0,
                    steps: 0,
                }
            })
            .collect();
        let size = reg.map_or(0, |r| usize::from(r.size));
        WheelWriter {
            reg,
            order,
            ids: config
                .joints
                .iter()
                .filter(|j| j.is_wheel())
                .map(|j| j.id)
                .collect(),
            data: vec![0; wheels.len() * size],
            wheels,
            dt,
        }
    }

    /// Whether the bus has wheels.
    pub fn any(&self) -> bool {
        !self.wheels.is_empty()
    }

    /// The wheel of joint `i` of the bus, if it is one.
    pub fn of_joint(&self, i: usize) -> Option<&WheelGoal> {
        self.wheels.iter().find(|w| w.bus_index == i)
    }

    /// Sets every wheel's target from `speeds` (robot order, rad/s; a wheel
    /// missing there heads for 0) and takes one ramp step.
    ///
    /// Without jerk limits the wheels ramp together: every wheel covers the
    /// same share of what is left to its target in a step, the share the
    /// wheel with the most to change can take within its acceleration, so
    /// that all arrive at once and the speeds keep their proportions on the
    /// way (a base keeps its direction of travel while it speeds up or
    /// brakes). A wheel with a jerk limit ramps on its own.
    pub fn aim(&mut self, speeds: &[f64]) {
        for w in &mut self.wheels {
            w.target = speeds.get(w.robot_index).copied().unwrap_or(0.0);
        }
        if self.wheels.iter().any(|w| w.max_jerk.is_some()) || self.dt <= 0.0 {
            for w in &mut self.wheels {
                w.step(self.dt);
            }
            return;
        }
        let share = self
            .wheels
            .iter()
            .map(|w| {
                let d = (w.target.clamp(-w.max_velocity, w.max_velocity) - w.speed).abs();
                if d > 0.0 {
                    (w.max_acceleration * self.dt / d).min(1.0)
                } else {
                    1.0
                }
            })
            .fold(1.0f64, f64::min);
        for w in &mut self.wheels {
            w.toward(share, self.dt);
        }
    }

    /// Whether every wheel is commanded to rest and heads for it.
    pub fn at_rest(&self) -> bool {
        self.wheels
            .iter()
            .all(|w| w.speed.abs() < REST && w.target.abs() < REST && w.accel.abs() < REST)
    }

    /// Commands rest at once (torque is going off: no ramp is possible).
    pub fn halt(&mut self) {
        for w in &mut self.wheels {
            (w.speed, w.accel, w.target) = (0.0, 0.0, 0.0);
        }
    }

    fn encode(&mut self) {
        let Some(reg) = self.reg else { return };
        let size = usize::from(reg.size);
        for (w, out) in self.wheels.iter_mut().zip(self.data.chunks_exact_mut(size)) {
            w.steps = w.steps(reg);
            // Kept in the register's range above, so it always encodes.
            let _ = reg.encode(w.steps, self.order, out);
        }
    }

    /// Sends the goal speeds (nothing on a bus without wheels), patiently.
    pub fn send_checked<T: Transport>(&mut self, bus: &mut Bus<T>) -> Result<(), BusError> {
        self.encode();
        match self.reg {
            Some(reg) if self.any() => bus.sync_write(reg.address, &self.ids, &self.data),
            _ => Ok(()),
        }
    }

    /// Sends the goal speeds in a cycle: only a lost port is an error.
    pub fn send<T: Transport>(&mut self, bus: &mut Bus<T>) -> Result<(), PortGone> {
        PortGone::check(self.send_checked(bus)).map(|_| ())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wheel(jerk: Option<f64>) -> WheelGoal {
        WheelGoal {
            bus_index: 0,
            robot_index: 0,
            steps_per_rad: 4096.0 / std::f64::consts::TAU,
            max_velocity: 3.0,
            max_acceleration: 6.0,
            max_jerk: jerk,
            speed: 0.0,
            accel: 0.0,
            target: 0.0,
            peak: 0.0,
            steps: 0,
        }
    }

    /// Steps `w` toward `target` for `n` steps of 5 ms; returns the speeds.
    fn run(w: &mut WheelGoal, target: f64, n: usize) -> Vec<f64> {
        w.target = target;
        (0..n)
            .map(|_| {
                w.step(0.005);
                w.speed
            })
            .collect()
    }

    #[test]
    fn the_ramp_keeps_to_the_limits_and_lands_on_the_target() {
        for jerk in [None, Some(60.0)] {
            let mut w = wheel(jerk);
            let mut last = 0.0;
            for target in [2.0, -2.5, 9.0, 0.0] {
                let speeds = run(&mut w, target, 600);
                for s in &speeds {
                    assert!(
                        (s - last).abs() <= 6.0 * 0.005 + 1e-12,
                        "{jerk:?} {s} {last}"
                    );
                    last = *s;
                }
                let want = target.clamp(-3.0, 3.0);
                assert_eq!(w.speed, want, "{jerk:?}");
                // No overshoot on the way.
                let beyond = speeds
                    .iter()
                    .any(|s| (s - want) * (want - speeds[0]) > 1e-9);
                assert!(!beyond, "{jerk:?} {target}");
            }
            assert!(w.peak <= 3.0 && w.peak > 2.9, "{}", w.peak);
        }
    }

    #[test]
    fn with_a_jerk_limit_the_acceleration_ramps() {
        let mut w = wheel(Some(60.0));
        let speeds = run(&mut w, 2.0, 400);
        let accel: Vec<f64> = speeds.windows(2).map(|p| (p[1] - p[0]) / 0.005).collect();
        // The step that lands on the target ends what acceleration is left
        // (less than two jerk steps); every step before it keeps to one.
        let landed = speeds.iter().position(|&s| s == 2.0).expect("lands");
        assert!(landed > 20, "{landed}");
        for a in accel[..landed - 1].windows(2) {
            assert!((a[1] - a[0]).abs() <= 60.0 * 0.005 + 1e-9, "{a:?}");
        }
        assert!(accel[landed - 2].abs() <= 2.0 * 60.0 * 0.005, "{accel:?}");
    }

    #[test]
    fn wheels_ramp_together_keeping_their_proportions() {
        let mut wheels = WheelWriter {
            reg: None,
            order: ByteOrder::Little,
            ids: vec![1, 2, 3],
            data: Vec::new(),
            wheels: (0..3)
                .map(|i| WheelGoal {
                    robot_index: i,
                    bus_index: i,
                    ..wheel(None)
                })
                .collect(),
            dt: 0.005,
        };
        // A base's wheels: one has twice as far to go as the others.
        let target = [1.0, -1.0, 2.0];
        let mut steps = 0;
        while !wheels
            .wheels
            .iter()
            .zip(&target)
            .all(|(w, t)| w.speed == *t)
        {
            steps += 1;
            assert!(steps < 1000, "never arrived");
            wheels.aim(&target);
            let s: Vec<f64> = wheels.wheels.iter().map(|w| w.speed).collect();
            // In proportion all the way, and within every acceleration.
            assert!(
                (s[2] - 2.0 * s[0]).abs() < 1e-12 && (s[1] + s[0]).abs() < 1e-12,
                "{s:?}"
            );
            assert!(wheels.wheels.iter().all(|w| w.accel.abs() <= 6.0 + 1e-9));
        }
        // The wheel with the most to change sets the pace: 2 rad/s at 6.
        assert_eq!(steps, (2.0f64 / (6.0 * 0.005)).ceil() as usize);
        // Braking to rest from there, together too.
        wheels.aim(&[0.0; 3]);
        let s: Vec<f64> = wheels.wheels.iter().map(|w| w.speed).collect();
        assert!((s[2] - 2.0 * s[0]).abs() < 1e-12 && s[2] < 2.0, "{s:?}");
    }

    #[test]
    fn speeds_become_steps_in_the_register_range() {
        let reg = servobus_protocol::registers::Series::Sts
            .map()
            .at(servobus_protocol::registers::addr::GOAL_SPEED)
            .expect("goal speed");
        let mut w = wheel(None);
        w.speed = -1.0;
        assert_eq!(w.steps(reg), -652);
        w.speed = 1e9;
        assert_eq!(w.steps(reg), reg.range().1);
        w.speed = f64::NAN;
        assert_eq!(w.steps(reg), 0);
    }
}
