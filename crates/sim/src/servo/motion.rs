//! The joint a simulated servo drives: stepping its dynamics (and its
//! body, when mounted), protection, and the present-value registers it
//! reports.

use std::time::Duration;

use super::{addr, SimServo};
use crate::body::{turn_delta, Body};
use crate::dynamics::{Drive, MAX_STEP_S};
use crate::model::{CURRENT_BIT, LOAD_BIT, SPEED_BIT};
use servobus_protocol::registers::{sign_magnitude, to_sign_magnitude};
use servobus_protocol::StatusFlags;

impl SimServo {
    /// Steps the dynamics to time `t` (never backwards) and refreshes the
    /// present-value registers.
    pub fn advance_to(&mut self, t: Duration) {
        if t <= self.time {
            return;
        }
        let mut left = (t - self.time).as_secs_f64();
        let end = t.as_secs_f64();
        self.time = t;
        while left > 0.0 {
            let mut drive = self.drive();
            let mut dt = if self.joint.quiescent(&drive) {
                left
            } else {
                left.min(MAX_STEP_S)
            };
            let now = end - left;
            if let Some(b) = &self.body {
                dt = body_step(b, now, dt).min(left);
                if drive.torque_on {
                    drive.load += b.hand_load(now);
                    drive.blocked |= b.blocked_by_stop(self.joint.ref_pos - self.joint.pos);
                }
            }
            let before = self.joint.pos;
            self.joint.step(&drive, dt);
            left -= dt;
            self.settle_body(now, end - left.max(0.0), dt, before, drive.torque_on);
            self.protect();
        }
        self.sync_outputs();
    }

    /// Brings the body in line with the shaft after a step from `t0` to
    /// `t1` (the shaft started at `before`): the hand moves a torque-off
    /// joint, the stops hold it, and the truth is recorded.
    pub(super) fn settle_body(&mut self, t0: f64, t1: f64, dt: f64, before: f64, torque_on: bool) {
        let raw = self.raw_of_pos(self.joint.pos);
        let Some(b) = &mut self.body else {
            return;
        };
        let a0 = b.angle;
        let settled = b.settle(raw, t1, torque_on);
        let full_turn = b.full_turn();
        if let Some(raw) = settled {
            let pos = self.pos_of_raw(raw);
            let turn = f64::from(self.model.model.resolution);
            let moved = if full_turn {
                turn_delta(pos, before, turn)
            } else {
                pos - before
            };
            self.joint.pos = pos;
            self.joint.vel = if dt > 0.0 { moved / dt } else { 0.0 };
            if !torque_on {
                self.joint.ref_pos = raw;
            }
        }
        if let Some(b) = &self.body {
            b.record(t0, t1, a0);
        }
    }

    /// The shift between the joint's frame and the present-position frame
    /// (`present = joint - shift`). A bare shaft is simulated in the
    /// sensor's raw frame, so the shift is the homing offset. A mounted
    /// servo is simulated in the present frame, as the real servo's
    /// position loop runs: the homing offset moves the seam the servo
    /// cannot cross with torque on, which is what calibration relies on.
    pub(super) fn shift(&self) -> i32 {
        if self.body.is_some() {
            0
        } else {
            self.offset()
        }
    }

    /// The raw sensor position of joint-frame position `pos` (mounted servos).
    pub(super) fn raw_of_pos(&self, pos: f64) -> f64 {
        let res = f64::from(self.model.model.resolution);
        if self.body.is_some() {
            (pos + f64::from(self.offset())).rem_euclid(res)
        } else {
            pos
        }
    }

    /// The joint-frame position of raw sensor position `raw` (mounted servos).
    pub(super) fn pos_of_raw(&self, raw: f64) -> f64 {
        let res = f64::from(self.model.model.resolution);
        if self.body.is_some() {
            (raw - f64::from(self.offset())).rem_euclid(res)
        } else {
            raw
        }
    }

    pub(super) fn offset(&self) -> i32 {
        match self.model.offset_sign_bit() {
            Some(bit) => self.read_signed(addr::OFFSET, bit),
            None => 0,
        }
    }

    pub(super) fn decode_position(&self, raw: u16) -> i32 {
        match self.model.position_sign_bit() {
            Some(bit) => sign_magnitude(u32::from(raw), bit),
            None => i32::from(raw),
        }
    }

    pub(super) fn encode_position(&self, v: i32) -> u32 {
        match self.model.position_sign_bit() {
            Some(bit) => to_sign_magnitude(v, bit),
            None => v.clamp(0, i32::from(u16::MAX)) as u32,
        }
    }

    /// The target in sensor ticks: the goal register, clamped to the angle
    /// limits (in the present frame), shifted by the homing offset.
    pub(super) fn target(&self) -> f64 {
        let mut goal = self.goal_position();
        let min = i32::from(self.read_u16(addr::MIN_ANGLE_LIMIT));
        let max = i32::from(self.read_u16(addr::MAX_ANGLE_LIMIT));
        if max > min {
            goal = goal.clamp(min, max);
        }
        let res = self.model.model.resolution as i32;
        f64::from((goal + self.shift()).rem_euclid(res))
    }

    pub(super) fn drive(&self) -> Drive {
        let m = self.model;
        let mode = if m.offset_sign_bit().is_some() {
            self.register(addr::MODE)
        } else {
            0
        };
        let goal_speed = self.read_signed(addr::GOAL_SPEED, SPEED_BIT);
        let max_speed = if goal_speed != 0 {
            f64::from(goal_speed.unsigned_abs()).min(m.max_speed())
        } else if let Some(v) = self.timed_speed {
            v.min(m.max_speed())
        } else {
            m.max_speed()
        };
        let acc = self.register(addr::ACCELERATION);
        let accel = if acc == 0 {
            f64::INFINITY
        } else {
            100.0 * f64::from(acc)
        };
        let dead_zone = f64::from(
            self.register(addr::CW_DEAD_ZONE)
                .max(self.register(addr::CCW_DEAD_ZONE)),
        );
        let max_torque = f64::from(self.read_u16(addr::MAX_TORQUE).min(1000)) / 1000.0;
        let torque_limit = if m.map().lock_address == addr::LOCK {
            (f64::from(self.read_u16(addr::TORQUE_LIMIT).min(1000)) / 1000.0).min(max_torque)
        } else {
            max_torque
        };
        let p = f64::from(self.register(addr::P_GAIN).max(1));
        Drive {
            torque_on: self.torque_enabled() && !self.unloaded(),
            wheel: mode == 1,
            lag_s: m.model.response_lag.as_secs_f64(),
            target: self.target(),
            wheel_speed: f64::from(goal_speed).clamp(-m.max_speed(), m.max_speed()),
            max_speed,
            accel,
            dead_zone,
            torque_limit,
            full_effort_error: (1600.0 / p) * f64::from(m.model.resolution) / 4096.0,
            load: self.load,
            blocked: self.blocked,
            max_pos: f64::from(m.model.max_position()),
            seamless: self.body.as_ref().is_some_and(Body::full_turn),
            ambient_c: self.ambient_c,
        }
    }

    /// Raises latched protection flags: overload after the protection time
    /// at the torque limit, overheat at the temperature limit (cleared 5 C
    /// below it). The torque is released while a latched flag is named by
    /// the unloading condition (register 19).
    pub(super) fn protect(&mut self) {
        let protection = if self.model.offset_sign_bit().is_some() {
            addr::PROTECTION_TIME
        } else {
            38
        };
        let protection_s = f64::from(self.register(protection)) * 0.01;
        if self.joint.stalled_s > protection_s.max(0.01) {
            self.latched |= StatusFlags::OVERLOAD;
        }
        let max_temp = f64::from(self.register(addr::MAX_TEMPERATURE));
        if self.joint.temp_c >= max_temp {
            self.latched |= StatusFlags::OVERHEAT;
        } else if self.joint.temp_c < max_temp - 5.0 {
            self.latched &= !StatusFlags::OVERHEAT;
        }
        self.update_flags();
    }

    pub(super) fn unloaded(&self) -> bool {
        self.latched & self.register(addr::UNLOADING_CONDITION) != 0
    }

    pub(super) fn voltage_dv(&self) -> u8 {
        let supply = self.supply_dv.unwrap_or(self.model.nominal_voltage());
        // The supply sags a little under load (cable and regulator losses).
        let sag = (3.0 * self.joint.effort.abs()).round() as u8;
        supply.saturating_sub(sag)
    }

    /// Recomputes the status register from latched, injected and voltage flags.
    pub(super) fn update_flags(&mut self) {
        let v = self.supply_dv.unwrap_or(self.model.nominal_voltage());
        let mut flags = self.latched | self.injected;
        if v > self.register(addr::MAX_VOLTAGE) || v < self.register(addr::MIN_VOLTAGE) {
            flags |= StatusFlags::VOLTAGE;
        }
        self.table[usize::from(addr::STATUS)] = flags;
    }

    /// Writes the joint's state into the present-value registers.
    pub(super) fn sync_outputs(&mut self) {
        let res = self.model.model.resolution as i32;
        let pos = (self.joint.pos.round() as i32 - self.shift()).rem_euclid(res);
        let raw = self.encode_position(pos);
        self.write_u16_raw(addr::PRESENT_POSITION, raw, false);
        if !self.torque_enabled() && !self.goal_given {
            // With torque off the goal follows the shaft, so that enabling
            // torque holds the joint where it is.
            self.write_u16_raw(addr::GOAL_POSITION, raw, false);
        }
        let speed = self.joint.vel.round().clamp(-32767.0, 32767.0) as i32;
        self.write_u16_raw(
            addr::PRESENT_SPEED,
            to_sign_magnitude(speed, SPEED_BIT),
            false,
        );
        let load = (self.joint.effort * 1000.0).round() as i32;
        self.write_u16_raw(addr::PRESENT_LOAD, to_sign_magnitude(load, LOAD_BIT), false);
        self.table[usize::from(addr::PRESENT_VOLTAGE)] = self.voltage_dv();
        self.table[usize::from(addr::PRESENT_TEMPERATURE)] =
            self.joint.temp_c.round().clamp(0.0, 255.0) as u8;
        let moving = self.joint.vel != 0.0 || self.joint.ref_vel != 0.0;
        self.table[usize::from(addr::MOVING)] = u8::from(moving);
        if self.model.stall_current > 0.0 {
            let idle = if self.torque_enabled() { 2.0 } else { 0.0 };
            let current =
                (self.joint.effort.abs() * self.model.stall_current + idle).round() as i32;
            self.write_u16_raw(
                addr::PRESENT_CURRENT,
                to_sign_magnitude(current, CURRENT_BIT),
                false,
            );
        }
    }
}

/// The length of the next step of a mounted servo from `now`, given the
/// dynamics' own choice `dt`: short steps while a hand holds the joint, and
/// no step past the moment a hand takes hold.
fn body_step(b: &Body, now: f64, dt: f64) -> f64 {
    let mut dt = dt;
    if b.hand_active(now, now + dt) {
        dt = dt.min(MAX_STEP_S);
    }
    if let Some(start) = b.hand_starts_after(now) {
        // Never a zero step: time must move on.
        dt = dt.min(start - now).max(1e-9);
    }
    dt
}
