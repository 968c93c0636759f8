//! One simulated servo: its memory table, the instructions it obeys and the
//! joint it drives.

use std::time::Duration;

use servobus_protocol::registers::{
    read_uint, return_delay_from_register, return_delay_register, sign_magnitude, Access,
};
use servobus_protocol::StatusFlags;

use crate::body::{Body, HandPath, Mount, Truth};
use crate::dynamics::Joint;
use crate::model::{SimModel, LOAD_BIT, SPEED_BIT};

// The servo's behaviour, by concern: the instructions it obeys and the
// memory writes they make, and the joint it drives with what it reports.
mod instructions;
mod motion;

/// Addresses shared by every model's layout (those of the protocol crate's
/// register maps).
pub use servobus_protocol::registers::addr;

/// A simulated Feetech servo.
///
/// It holds the model's memory table byte for byte and answers instruction
/// packets as the real servo does (see the crate docs for the rules), and it
/// drives a simulated joint stepped from the time it is given.
#[derive(Debug, Clone)]
pub struct SimServo {
    model: &'static SimModel,
    table: Vec<u8>,
    /// What the EEPROM holds: the table after a power cycle.
    saved: Vec<u8>,
    /// A REG WRITE waiting for ACTION: address and data.
    pending: Option<(u8, Vec<u8>)>,
    joint: Joint,
    /// Whether a goal was written since torque was last switched off (until
    /// then the goal register follows the present position).
    goal_given: bool,
    /// Profile top speed from the goal time, when that is what limits it.
    timed_speed: Option<f64>,
    time: Duration,
    offline: bool,
    blocked: bool,
    load: f64,
    supply_dv: Option<u8>,
    ambient_c: f64,
    injected: u8,
    latched: u8,
    /// The joint the servo is mounted on, when it has one.
    body: Option<Body>,
}

impl SimServo {
    /// A servo of `model` with ID `id`, saved in its EEPROM, every other
    /// register at its factory value, the shaft at mid-travel.
    pub fn new(model: &'static SimModel, id: u8) -> SimServo {
        let mut table = model.factory_table();
        table[usize::from(addr::ID)] = id;
        let saved = table.clone();
        let mid = f64::from(model.model.resolution / 2);
        let mut servo = SimServo {
            model,
            table,
            saved,
            pending: None,
            joint: Joint::at(mid, 25.0),
            goal_given: false,
            timed_speed: None,
            time: Duration::ZERO,
            offline: false,
            blocked: false,
            load: 0.0,
            supply_dv: None,
            ambient_c: 25.0,
            injected: 0,
            latched: 0,
            body: None,
        };
        servo.sync_outputs();
        servo
    }

    /// An STS3215 with ID `id`.
    pub fn sts3215(id: u8) -> SimServo {
        SimServo::new(&SimModel::STS3215, id)
    }

    /// An STS3250 with ID `id`.
    pub fn sts3250(id: u8) -> SimServo {
        SimServo::new(&SimModel::STS3250, id)
    }

    /// An SCS0009 (big-endian SCS series) with ID `id`.
    pub fn scs0009(id: u8) -> SimServo {
        SimServo::new(&SimModel::SCS0009, id)
    }

    /// The same servo with its shaft at `ticks` (present-position frame).
    #[must_use]
    pub fn with_position(mut self, ticks: i32) -> SimServo {
        self.move_joint(ticks);
        self
    }

    /// The same servo with return delay `delay` saved in its EEPROM
    /// (rounded down to the register's 2 us units, at most 510 us).
    #[must_use]
    pub fn with_return_delay(mut self, delay: Duration) -> SimServo {
        self.set_saved(addr::RETURN_DELAY, return_delay_register(delay));
        self
    }

    /// The same servo with status level `level` saved in its EEPROM.
    #[must_use]
    pub fn with_status_level(mut self, level: u8) -> SimServo {
        self.set_saved(addr::STATUS_LEVEL, level);
        self
    }

    /// The same servo with the byte at `address` set to `value` and saved,
    /// bypassing access rules (to build a servo as it left a setup tool).
    #[must_use]
    pub fn with_byte(mut self, address: u8, value: u8) -> SimServo {
        self.set_saved(address, value);
        self
    }

    /// The same servo mounted on a joint by `mount`, the joint at physical
    /// `angle_deg` (clamped to the stops). From now on the shaft's sensor
    /// reads `(zero_tick + direction * angle * ticks_per_deg) mod
    /// resolution` (see [`crate::body`]), the shaft turns freely past the
    /// seam of a full-turn sensor, and [`SimServo::joint_angle`] is the
    /// joint's physical angle.
    #[must_use]
    pub fn with_mount(mut self, mount: Mount, angle_deg: f64) -> SimServo {
        let mut body = Body::new(mount, angle_deg, &self.model.model);
        if let Some(old) = self.body.take() {
            body.hand = old.hand;
            body.truth = old.truth;
        }
        let raw = body.raw_of(body.angle);
        self.body = Some(body);
        self.joint.pos = self.pos_of_raw(raw);
        self.joint.ref_pos = self.joint.pos;
        self.joint.vel = 0.0;
        self.joint.ref_vel = 0.0;

        self.sync_outputs();
        self
    }

    /// The same servo with a hand on its joint (see [`HandPath`]); the
    /// servo must have been mounted ([`SimServo::with_mount`]) first, or
    /// the hand is ignored.
    #[must_use]
    pub fn with_hand(mut self, hand: HandPath) -> SimServo {
        self.set_hand(Some(hand));
        self
    }

    /// The same servo writing its joint's physical angle into column
    /// `column` of `truth`; ignored without a mounting.
    #[must_use]
    pub fn with_truth(mut self, truth: &Truth, column: usize) -> SimServo {
        if let Some(b) = &mut self.body {
            b.truth = Some((truth.clone(), column));
        }
        self
    }

    /// Puts a hand on the joint or takes it away (`None`); ignored without
    /// a mounting.
    pub fn set_hand(&mut self, hand: Option<HandPath>) {
        if let Some(b) = &mut self.body {
            b.hand = hand;
        }
    }

    /// The mounting, if the servo has one.
    pub fn mount(&self) -> Option<Mount> {
        self.body.as_ref().map(|b| b.mount)
    }

    /// The joint's physical angle in degrees, if the servo is mounted.
    pub fn joint_angle(&self) -> Option<f64> {
        self.body.as_ref().map(|b| b.angle)
    }

    /// The raw sensor position in ticks (before the homing offset), rounded
    /// as the sensor reports it.
    pub fn raw_position(&self) -> i32 {
        let raw = self.raw_of_pos(self.joint.pos);
        (raw.round() as i32).rem_euclid(self.model.model.resolution as i32)
    }

    fn set_saved(&mut self, address: u8, value: u8) {
        let a = usize::from(address);
        if a < self.table.len() {
            self.table[a] = value;
            self.saved[a] = value;
        }
        self.after_write(address, 1);
    }

    /// The model.
    pub fn model(&self) -> &'static SimModel {
        self.model
    }

    /// The current ID (register 5).
    pub fn id(&self) -> u8 {
        self.table[usize::from(addr::ID)]
    }

    /// The baud-rate index (register 6).
    pub fn baud_index(&self) -> u8 {
        self.table[usize::from(addr::BAUD_RATE)]
    }

    /// The return delay (register 7, 2 us units).
    pub fn return_delay(&self) -> Duration {
        return_delay_from_register(self.register(addr::RETURN_DELAY))
    }

    /// The time the servo's state was last stepped to.
    pub fn time(&self) -> Duration {
        self.time
    }

    /// One byte of the memory table (0 past its end).
    pub fn register(&self, address: u8) -> u8 {
        self.table.get(usize::from(address)).copied().unwrap_or(0)
    }

    /// `len` bytes of the memory table from `address`, as a READ answers
    /// them (zeros past the table's end).
    pub fn read(&self, address: u8, len: usize) -> Vec<u8> {
        (0..len)
            .map(|i| {
                self.table
                    .get(usize::from(address) + i)
                    .copied()
                    .unwrap_or(0)
            })
            .collect()
    }

    /// A two-byte register as an unsigned value, in the model's byte order.
    pub fn read_u16(&self, address: u8) -> u16 {
        let b = [
            self.register(address),
            self.register(address.wrapping_add(1)),
        ];
        read_uint(&b, self.model.byte_order()) as u16
    }

    /// A two-byte sign-magnitude register whose direction bit is `sign_bit`.
    pub(super) fn read_signed(&self, address: u8, sign_bit: u8) -> i32 {
        sign_magnitude(u32::from(self.read_u16(address)), sign_bit)
    }

    /// Present position (register 56) as a signed value.
    pub fn present_position(&self) -> i32 {
        self.decode_position(self.read_u16(addr::PRESENT_POSITION))
    }

    /// Goal position (register 42) as a signed value.
    pub fn goal_position(&self) -> i32 {
        self.decode_position(self.read_u16(addr::GOAL_POSITION))
    }

    /// Present speed (register 58) in ticks/s, signed.
    pub fn present_speed(&self) -> i32 {
        self.read_signed(addr::PRESENT_SPEED, SPEED_BIT)
    }

    /// Present load (register 60) in 0.1 % of the maximum torque, signed.
    pub fn present_load(&self) -> i32 {
        self.read_signed(addr::PRESENT_LOAD, LOAD_BIT)
    }

    /// The status flags the servo reports (register 65 and every reply).
    pub fn status(&self) -> StatusFlags {
        StatusFlags(self.register(addr::STATUS))
    }

    /// Whether torque is enabled (register 40).
    pub fn torque_enabled(&self) -> bool {
        self.register(addr::TORQUE_ENABLE) != 0
    }

    /// Whether the moving flag (register 66) is set.
    pub fn is_moving(&self) -> bool {
        self.register(addr::MOVING) != 0
    }

    /// The exact shaft position in the present-position frame, in ticks
    /// (unrounded, for tests of the dynamics).
    pub fn shaft_position(&self) -> f64 {
        self.joint.pos - f64::from(self.shift())
    }

    /// Writes `data` at `address` as a WRITE instruction would, access rules
    /// and lock included.
    pub fn write(&mut self, address: u8, data: &[u8]) {
        self.apply_write(address, data);
    }

    /// Sets bytes regardless of access (to put a read-only register into a
    /// state for a test); the next dynamics step may overwrite present values.
    pub fn poke(&mut self, address: u8, data: &[u8]) {
        for (i, &v) in data.iter().enumerate() {
            if let Some(b) = self.table.get_mut(usize::from(address) + i) {
                *b = v;
            }
        }
        self.after_write(address, data.len());
    }

    /// Moves the shaft to `ticks` in the present-position frame, as a hand
    /// turning the horn would (with torque on, the servo then returns to its goal).
    pub fn move_joint(&mut self, ticks: i32) {
        let max = f64::from(self.model.model.max_position());
        let mut pos = f64::from(ticks) + f64::from(self.shift());
        pos = match &self.body {
            Some(b) if b.full_turn() => pos.rem_euclid(max + 1.0),
            _ => pos.clamp(0.0, max),
        };
        let raw = self.raw_of_pos(pos);
        let t = self.time.as_secs_f64();
        // The body follows (a hand turning the horn), within its stops.
        if let Some(raw) = self.body.as_mut().and_then(|b| b.settle(raw, t, true)) {
            pos = self.pos_of_raw(raw);
        }
        self.joint.pos = pos;
        self.joint.vel = 0.0;
        if !self.torque_enabled() {
            self.joint.ref_pos = pos;
        }
        self.sync_outputs();
    }

    /// Applies an external torque as a fraction of the servo's maximum
    /// (positive pushes towards lower positions, as gravity on a raised arm).
    /// With torque off the joint sags; with torque on it holds with a small
    /// error, or is pushed back and overloads when the load exceeds the torque limit.
    pub fn set_external_load(&mut self, fraction: f64) {
        self.load = if fraction.is_finite() { fraction } else { 0.0 };
    }

    /// Blocks the shaft mechanically: it stops where it is; with torque on
    /// the servo strains at its torque limit and raises overload after the
    /// protection time.
    pub fn set_blocked(&mut self, blocked: bool) {
        self.blocked = blocked;
    }

    /// Disconnects the servo from the bus (it hears and answers nothing) or
    /// reconnects it.
    pub fn set_offline(&mut self, offline: bool) {
        self.offline = offline;
    }

    /// Whether the servo is disconnected from the bus.
    pub fn is_offline(&self) -> bool {
        self.offline
    }

    /// Sets the supply voltage in 0.1 V (`None`: the model's nominal
    /// voltage); outside the limits of registers 14/15 the voltage flag rises.
    pub fn set_supply_voltage(&mut self, decivolts: Option<u8>) {
        self.supply_dv = decivolts;
        self.sync_outputs();
    }

    /// Sets the motor temperature at once (the overheat flag rises at or
    /// above register 13) and the ambient temperature it cools towards.
    pub fn set_temperature(&mut self, celsius: f64, ambient_c: f64) {
        if celsius.is_finite() {
            self.joint.temp_c = celsius;
        }
        if ambient_c.is_finite() {
            self.ambient_c = ambient_c;
        }
        self.update_flags();
        self.sync_outputs();
    }

    /// Forces status bits on (or clears them with 0) regardless of the physics.
    pub fn inject_status(&mut self, flags: u8) {
        self.injected = flags;
        self.update_flags();
        self.sync_outputs();
    }

    /// Switches the servo off and on: RAM returns to factory values, EEPROM
    /// keeps what was written with the lock open, a held REG WRITE is lost,
    /// torque is off and the goal follows the shaft.
    pub fn power_cycle(&mut self) {
        let factory = self.model.factory_table();
        for (a, b) in self.table.iter_mut().enumerate() {
            *b = match self.model.area(a) {
                Access::Eeprom => self.saved[a],
                _ => factory[a],
            };
        }
        self.joint.stalled_s = 0.0;
        self.restart();
    }

    /// What a power cycle and a RESET both do once the table is set: forget
    /// the held REG WRITE, the goal, a timed move and latched errors, hold
    /// where the shaft is, and show the new table.
    fn restart(&mut self) {
        self.pending = None;
        self.goal_given = false;
        self.timed_speed = None;
        self.latched = 0;
        self.joint.ref_pos = self.joint.pos;
        self.joint.ref_vel = 0.0;
        self.update_flags();
        self.sync_outputs();
    }
}
