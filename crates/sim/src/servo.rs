//! One simulated servo: its memory table, the instructions it obeys and the
//! joint it drives.

use std::time::Duration;

use servobus_protocol::{encode, Instruction, Packet, StatusFlags, BROADCAST_ID};

use crate::body::{Body, HandPath, Mount, Truth};
use crate::dynamics::{Drive, Joint, MAX_STEP_S};
use crate::model::{from_sign_magnitude, sign_magnitude, Area, Endian, SimModel};
use crate::model::{CURRENT_BIT, LOAD_BIT, SPEED_BIT};

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
        let mid = f64::from(model.resolution / 2);
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
        let units = (delay.as_micros() / 2).min(255) as u8;
        self.set_saved(addr::RETURN_DELAY, units);
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
        let mut body = Body::new(
            mount,
            angle_deg,
            self.model.resolution,
            self.model.range_deg,
        );
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
        (raw.round() as i32).rem_euclid(self.model.resolution as i32)
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
        Duration::from_micros(2 * u64::from(self.table[usize::from(addr::RETURN_DELAY)]))
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
        match self.model.endian {
            Endian::Little => u16::from_le_bytes(b),
            Endian::Big => u16::from_be_bytes(b),
        }
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
        from_sign_magnitude(self.read_u16(addr::PRESENT_SPEED), SPEED_BIT)
    }

    /// Present load (register 60) in 0.1 % of the maximum torque, signed.
    pub fn present_load(&self) -> i32 {
        from_sign_magnitude(self.read_u16(addr::PRESENT_LOAD), LOAD_BIT)
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
        let max = f64::from(self.model.resolution - 1);
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
                Area::Eeprom => self.saved[a],
                _ => factory[a],
            };
        }
        self.pending = None;
        self.goal_given = false;
        self.timed_speed = None;
        self.latched = 0;
        self.joint.ref_pos = self.joint.pos;
        self.joint.ref_vel = 0.0;
        self.joint.stalled_s = 0.0;
        self.update_flags();
        self.sync_outputs();
    }

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
    fn settle_body(&mut self, t0: f64, t1: f64, dt: f64, before: f64, torque_on: bool) {
        let raw = self.raw_of_pos(self.joint.pos);
        let Some(b) = &mut self.body else {
            return;
        };
        let a0 = b.angle;
        let settled = b.settle(raw, t1, torque_on);
        let full_turn = b.full_turn();
        if let Some(raw) = settled {
            let pos = self.pos_of_raw(raw);
            let turn = f64::from(self.model.resolution);
            let mut moved = pos - before;
            if full_turn {
                moved = (moved + turn / 2.0).rem_euclid(turn) - turn / 2.0;
            }
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

    /// Executes one instruction packet received at time `now` (the end of its
    /// last byte) and returns the status frame to send back, if any.
    ///
    /// Packets for other IDs, unknown instructions and instructions the model
    /// lacks (SYNC READ on SCS) are ignored. A SYNC READ reply is returned
    /// whatever the servo's place in the ID list: the bus orders the replies.
    pub fn handle(&mut self, packet: &Packet<'_>, now: Duration) -> Option<Vec<u8>> {
        if self.offline {
            return None;
        }
        self.advance_to(now);
        let id = self.id();
        let broadcast = packet.id() == BROADCAST_ID;
        if !broadcast && packet.id() != id {
            return None;
        }
        let inst = packet.instruction()?;
        let p = packet.params();
        let data: Option<Vec<u8>> = match inst {
            Instruction::Ping => Some(Vec::new()),
            Instruction::Read => {
                let [address, len] = *p else { return None };
                if broadcast {
                    return None;
                }
                Some(self.read(address, usize::from(len)))
            }
            Instruction::Write => {
                let (&address, bytes) = p.split_first()?;
                if bytes.is_empty() {
                    return None;
                }
                self.apply_write(address, bytes);
                Some(Vec::new())
            }
            Instruction::RegWrite => {
                let (&address, bytes) = p.split_first()?;
                if bytes.is_empty() {
                    return None;
                }
                self.pending = Some((address, bytes.to_vec()));
                self.table[usize::from(addr::ASYNC_FLAG)] = 1;
                Some(Vec::new())
            }
            Instruction::Action => {
                if let Some((address, bytes)) = self.pending.take() {
                    self.table[usize::from(addr::ASYNC_FLAG)] = 0;
                    self.apply_write(address, &bytes);
                }
                Some(Vec::new())
            }
            Instruction::Reset => {
                self.factory_reset();
                Some(Vec::new())
            }
            Instruction::SyncWrite => {
                let [address, len, ref blocks @ ..] = *p else {
                    return None;
                };
                let block = usize::from(len) + 1;
                if len == 0 || !broadcast {
                    return None;
                }
                if let Some(chunk) = blocks.chunks_exact(block).find(|c| c[0] == id) {
                    self.apply_write(address, &chunk[1..]);
                }
                None
            }
            Instruction::SyncRead => {
                let [address, len, ref ids @ ..] = *p else {
                    return None;
                };
                if !self.model.sync_read || !broadcast || !ids.contains(&id) {
                    return None;
                }
                return self.status_frame(id, &self.read(address, usize::from(len)));
            }
        };
        // Broadcast: only PING is answered.
        if broadcast && inst != Instruction::Ping {
            return None;
        }
        if !self.answers(inst) {
            return None;
        }
        // Replies come from the ID the packet was addressed to (the old ID
        // after an ID write).
        self.status_frame(id, &data.unwrap_or_default())
    }

    fn status_frame(&self, id: u8, params: &[u8]) -> Option<Vec<u8>> {
        let mut buf = vec![0u8; servobus_protocol::frame_len(params.len())];
        let n = encode::status(&mut buf, id, self.status(), params).ok()?;
        buf.truncate(n);
        Some(buf)
    }

    /// Whether the status level lets `inst` be answered.
    fn answers(&self, inst: Instruction) -> bool {
        let level = self.register(addr::STATUS_LEVEL);
        match (self.model.three_status_levels, inst) {
            (_, Instruction::Ping) => true,
            (false, Instruction::Read | Instruction::SyncRead) => true,
            (true, Instruction::Read) => level >= 1,
            (false, _) => level >= 1,
            (true, _) => level >= 2,
        }
    }

    /// RESET: every register back to its factory value and saved, except the
    /// ID, so that a reset servo stays addressable on a bus of many.
    fn factory_reset(&mut self) {
        let id = self.id();
        self.table = self.model.factory_table();
        self.table[usize::from(addr::ID)] = id;
        self.saved = self.table.clone();
        self.pending = None;
        self.goal_given = false;
        self.timed_speed = None;
        self.latched = 0;
        self.joint.ref_pos = self.joint.pos;
        self.joint.ref_vel = 0.0;
        self.update_flags();
        self.sync_outputs();
    }

    fn lock_open(&self) -> bool {
        self.register(self.model.lock_address) == 0
    }

    fn apply_write(&mut self, address: u8, data: &[u8]) {
        let torque_before = self.register(addr::TORQUE_ENABLE);
        let lock_open = self.lock_open();
        for (i, &v) in data.iter().enumerate() {
            let a = usize::from(address) + i;
            if a >= self.table.len() {
                break;
            }
            match self.model.area(a) {
                Area::ReadOnly => {}
                Area::Ram => self.table[a] = v,
                Area::Eeprom => {
                    self.table[a] = v;
                    if lock_open {
                        self.saved[a] = v;
                    }
                }
            }
        }
        let touched = |reg: u8| covers(address, data.len(), reg);
        if touched(addr::TORQUE_ENABLE) {
            self.torque_written(torque_before);
        }
        self.after_write(address, data.len());
    }

    /// Side effects of bytes changed at `address..address+len`.
    fn after_write(&mut self, address: u8, len: usize) {
        let touched = |reg: u8, size: usize| (0..size).any(|k| covers(address, len, reg + k as u8));
        if touched(addr::GOAL_POSITION, 2) {
            self.goal_given = true;
            let target = self.target();
            let t = f64::from(self.read_u16(addr::GOAL_TIME));
            self.timed_speed =
                (t > 0.0).then(|| ((target - self.joint.ref_pos).abs() / (t / 1000.0)).max(1.0));
        }
        if touched(addr::OFFSET, 2) && self.model.offset_sign_bit.is_some() {
            if let Some(raw) = self.body.as_ref().map(Body::raw) {
                // The shaft stays where it is; its reading moves with the
                // offset, and the servo holds the shaft where it now reads.
                let pos = self.pos_of_raw(raw);
                self.joint.pos = pos;
                self.joint.ref_pos = pos;
                self.joint.ref_vel = 0.0;
            }
        }
        if touched(addr::GOAL_TIME, 2) && self.read_u16(addr::GOAL_TIME) == 0 {
            self.timed_speed = None;
        }
        self.update_flags();
        self.sync_outputs();
    }

    fn torque_written(&mut self, before: u8) {
        let v = self.register(addr::TORQUE_ENABLE);
        if v == 128 {
            // Calibrate: the present position becomes the midpoint.
            if let Some(bit) = self.model.offset_sign_bit {
                let mid = (self.model.resolution / 2) as i32;
                let offset = self.raw_of_pos(self.joint.pos).round() as i32 - mid;
                let raw = sign_magnitude(offset, bit);
                self.write_u16_raw(addr::OFFSET, raw, true);
            }
            self.table[usize::from(addr::TORQUE_ENABLE)] = before;
            self.after_write(addr::OFFSET, 2);
            return;
        }
        if v == 0 {
            self.goal_given = false;
        } else {
            // Switching torque on clears the latched protection flags.
            self.latched = 0;
            self.joint.stalled_s = 0.0;
            if before == 0 && !self.goal_given {
                self.joint.ref_pos = self.joint.pos;
            }
        }
        self.update_flags();
    }

    fn write_u16_raw(&mut self, address: u8, raw: u16, persist: bool) {
        let b = match self.model.endian {
            Endian::Little => raw.to_le_bytes(),
            Endian::Big => raw.to_be_bytes(),
        };
        let a = usize::from(address);
        if a + 1 < self.table.len() {
            self.table[a..a + 2].copy_from_slice(&b);
            if persist && self.lock_open() {
                self.saved[a..a + 2].copy_from_slice(&b);
            }
        }
    }

    /// The shift between the joint's frame and the present-position frame
    /// (`present = joint - shift`). A bare shaft is simulated in the
    /// sensor's raw frame, so the shift is the homing offset. A mounted
    /// servo is simulated in the present frame, as the real servo's
    /// position loop runs: the homing offset moves the seam the servo
    /// cannot cross with torque on, which is what calibration relies on.
    fn shift(&self) -> i32 {
        if self.body.is_some() {
            0
        } else {
            self.offset()
        }
    }

    /// The raw sensor position of joint-frame position `pos` (mounted servos).
    fn raw_of_pos(&self, pos: f64) -> f64 {
        let res = f64::from(self.model.resolution);
        if self.body.is_some() {
            (pos + f64::from(self.offset())).rem_euclid(res)
        } else {
            pos
        }
    }

    /// The joint-frame position of raw sensor position `raw` (mounted servos).
    fn pos_of_raw(&self, raw: f64) -> f64 {
        let res = f64::from(self.model.resolution);
        if self.body.is_some() {
            (raw - f64::from(self.offset())).rem_euclid(res)
        } else {
            raw
        }
    }

    fn offset(&self) -> i32 {
        match self.model.offset_sign_bit {
            Some(bit) => from_sign_magnitude(self.read_u16(addr::OFFSET), bit),
            None => 0,
        }
    }

    fn decode_position(&self, raw: u16) -> i32 {
        match self.model.position_sign_bit {
            Some(bit) => from_sign_magnitude(raw, bit),
            None => i32::from(raw),
        }
    }

    fn encode_position(&self, v: i32) -> u16 {
        match self.model.position_sign_bit {
            Some(bit) => sign_magnitude(v, bit),
            None => v.clamp(0, i32::from(u16::MAX)) as u16,
        }
    }

    /// The target in sensor ticks: the goal register, clamped to the angle
    /// limits (in the present frame), shifted by the homing offset.
    fn target(&self) -> f64 {
        let mut goal = self.goal_position();
        let min = i32::from(self.read_u16(addr::MIN_ANGLE_LIMIT));
        let max = i32::from(self.read_u16(addr::MAX_ANGLE_LIMIT));
        if max > min {
            goal = goal.clamp(min, max);
        }
        let res = self.model.resolution as i32;
        f64::from((goal + self.shift()).rem_euclid(res))
    }

    fn drive(&self) -> Drive {
        let m = self.model;
        let mode = if m.offset_sign_bit.is_some() {
            self.register(addr::MODE)
        } else {
            0
        };
        let goal_speed = from_sign_magnitude(self.read_u16(addr::GOAL_SPEED), SPEED_BIT);
        let max_speed = if goal_speed != 0 {
            f64::from(goal_speed.unsigned_abs()).min(m.max_speed)
        } else if let Some(v) = self.timed_speed {
            v.min(m.max_speed)
        } else {
            m.max_speed
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
        let torque_limit = if m.lock_address == addr::LOCK {
            (f64::from(self.read_u16(addr::TORQUE_LIMIT).min(1000)) / 1000.0).min(max_torque)
        } else {
            max_torque
        };
        let p = f64::from(self.register(addr::P_GAIN).max(1));
        Drive {
            torque_on: self.torque_enabled() && !self.unloaded(),
            wheel: mode == 1,
            target: self.target(),
            wheel_speed: f64::from(goal_speed).clamp(-m.max_speed, m.max_speed),
            max_speed,
            accel,
            dead_zone,
            torque_limit,
            full_effort_error: (1600.0 / p) * f64::from(m.resolution) / 4096.0,
            load: self.load,
            blocked: self.blocked,
            max_pos: f64::from(m.resolution - 1),
            seamless: self.body.as_ref().is_some_and(Body::full_turn),
            ambient_c: self.ambient_c,
        }
    }

    /// Raises latched protection flags: overload after the protection time
    /// at the torque limit, overheat at the temperature limit (cleared 5 C
    /// below it). The torque is released while a latched flag is named by
    /// the unloading condition (register 19).
    fn protect(&mut self) {
        let protection = if self.model.offset_sign_bit.is_some() {
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

    fn unloaded(&self) -> bool {
        self.latched & self.register(addr::UNLOADING_CONDITION) != 0
    }

    fn voltage_dv(&self) -> u8 {
        let supply = self.supply_dv.unwrap_or(self.model.nominal_voltage);
        // The supply sags a little under load (cable and regulator losses).
        let sag = (3.0 * self.joint.effort.abs()).round() as u8;
        supply.saturating_sub(sag)
    }

    /// Recomputes the status register from latched, injected and voltage flags.
    fn update_flags(&mut self) {
        let v = self.supply_dv.unwrap_or(self.model.nominal_voltage);
        let mut flags = self.latched | self.injected;
        if v > self.register(addr::MAX_VOLTAGE) || v < self.register(addr::MIN_VOLTAGE) {
            flags |= StatusFlags::VOLTAGE;
        }
        self.table[usize::from(addr::STATUS)] = flags;
    }

    /// Writes the joint's state into the present-value registers.
    fn sync_outputs(&mut self) {
        let res = self.model.resolution as i32;
        let pos = (self.joint.pos.round() as i32 - self.shift()).rem_euclid(res);
        let raw = self.encode_position(pos);
        self.write_u16_raw(addr::PRESENT_POSITION, raw, false);
        if !self.torque_enabled() && !self.goal_given {
            // With torque off the goal follows the shaft, so that enabling
            // torque holds the joint where it is.
            self.write_u16_raw(addr::GOAL_POSITION, raw, false);
        }
        let speed = self.joint.vel.round().clamp(-32767.0, 32767.0) as i32;
        self.write_u16_raw(addr::PRESENT_SPEED, sign_magnitude(speed, SPEED_BIT), false);
        let load = (self.joint.effort * 1000.0).round() as i32;
        self.write_u16_raw(addr::PRESENT_LOAD, sign_magnitude(load, LOAD_BIT), false);
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
                sign_magnitude(current, CURRENT_BIT),
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

/// Whether the write of `len` bytes at `address` covers byte `reg`.
fn covers(address: u8, len: usize, reg: u8) -> bool {
    let a = usize::from(address);
    (a..a + len).contains(&usize::from(reg))
}
