//! The instructions a simulated servo obeys, and what writes to its memory
//! table do: the EEPROM lock, torque, homing offset, factory reset.

use std::time::Duration;

use servobus_protocol::registers::{to_sign_magnitude, write_uint, Access};
use servobus_protocol::{encode, Instruction, Packet, BROADCAST_ID};

use super::{addr, SimServo};
use crate::body::Body;

impl SimServo {
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
        let data = match inst {
            Instruction::Ping => Vec::new(),
            Instruction::Read => self.exec_read(p, broadcast)?,
            Instruction::Write => {
                self.exec_write(p)?;
                Vec::new()
            }
            Instruction::RegWrite => {
                self.exec_reg_write(p)?;
                Vec::new()
            }
            Instruction::Action => {
                self.exec_action();
                Vec::new()
            }
            Instruction::Reset => {
                self.factory_reset();
                Vec::new()
            }
            Instruction::SyncWrite => {
                // Always a broadcast, never answered.
                self.exec_sync_write(p, id, broadcast);
                return None;
            }
            Instruction::SyncRead => return self.exec_sync_read(p, id, broadcast),
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
        self.status_frame(id, &data)
    }

    /// READ: the requested bytes (`None`, ignored, when malformed or broadcast).
    fn exec_read(&self, p: &[u8], broadcast: bool) -> Option<Vec<u8>> {
        let [address, len] = *p else { return None };
        if broadcast {
            return None;
        }
        Some(self.read(address, usize::from(len)))
    }

    /// WRITE: applies the bytes at once (`None`, ignored, when malformed).
    fn exec_write(&mut self, p: &[u8]) -> Option<()> {
        let (&address, bytes) = p.split_first()?;
        if bytes.is_empty() {
            return None;
        }
        self.apply_write(address, bytes);
        Some(())
    }

    /// REG WRITE: keeps the bytes for the next ACTION (`None`, ignored, when
    /// malformed).
    fn exec_reg_write(&mut self, p: &[u8]) -> Option<()> {
        let (&address, bytes) = p.split_first()?;
        if bytes.is_empty() {
            return None;
        }
        self.pending = Some((address, bytes.to_vec()));
        self.table[usize::from(addr::ASYNC_FLAG)] = 1;
        Some(())
    }

    /// ACTION: applies the write a REG WRITE left pending, if any.
    fn exec_action(&mut self) {
        if let Some((address, bytes)) = self.pending.take() {
            self.table[usize::from(addr::ASYNC_FLAG)] = 0;
            self.apply_write(address, &bytes);
        }
    }

    /// SYNC WRITE: applies this servo's block, if the broadcast has one.
    fn exec_sync_write(&mut self, p: &[u8], id: u8, broadcast: bool) {
        let [address, len, ref blocks @ ..] = *p else {
            return;
        };
        let block = usize::from(len) + 1;
        if len == 0 || !broadcast {
            return;
        }
        if let Some(chunk) = blocks.chunks_exact(block).find(|c| c[0] == id) {
            self.apply_write(address, &chunk[1..]);
        }
    }

    /// SYNC READ: the status frame with the requested bytes, when the model
    /// has the instruction, the servo is in the ID list and it answers.
    fn exec_sync_read(&self, p: &[u8], id: u8, broadcast: bool) -> Option<Vec<u8>> {
        let [address, len, ref ids @ ..] = *p else {
            return None;
        };
        let supported = self.model.model.series.has_sync_read();
        if !supported || !broadcast || !ids.contains(&id) || !self.answers(Instruction::SyncRead) {
            return None;
        }
        self.status_frame(id, &self.read(address, usize::from(len)))
    }

    pub(super) fn status_frame(&self, id: u8, params: &[u8]) -> Option<Vec<u8>> {
        let mut buf = vec![0u8; servobus_protocol::frame_len(params.len())];
        let n = encode::status(&mut buf, id, self.status(), params).ok()?;
        buf.truncate(n);
        Some(buf)
    }

    /// Whether the status level (register 8) lets `inst` be answered.
    pub(super) fn answers(&self, inst: Instruction) -> bool {
        let level = self.model.status_level(self.register(addr::STATUS_LEVEL));
        level.answers(inst)
    }

    /// RESET: every register back to its factory value and saved, except the
    /// ID, so that a reset servo stays addressable on a bus of many.
    pub(super) fn factory_reset(&mut self) {
        let id = self.id();
        self.table = self.model.factory_table();
        self.table[usize::from(addr::ID)] = id;
        self.saved = self.table.clone();
        self.restart();
    }

    pub(super) fn lock_open(&self) -> bool {
        self.register(self.model.map().lock_address) == 0
    }

    pub(super) fn apply_write(&mut self, address: u8, data: &[u8]) {
        let torque_before = self.register(addr::TORQUE_ENABLE);
        let lock_open = self.lock_open();
        for (i, &v) in data.iter().enumerate() {
            let a = usize::from(address) + i;
            if a >= self.table.len() {
                break;
            }
            match self.model.area(a) {
                Access::ReadOnly => {}
                Access::Ram => self.table[a] = v,
                Access::Eeprom => {
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
    pub(super) fn after_write(&mut self, address: u8, len: usize) {
        let touched = |reg: u8, size: usize| (0..size).any(|k| covers(address, len, reg + k as u8));
        if touched(addr::GOAL_POSITION, 2) {
            self.goal_given = true;
            let target = self.target();
            let t = f64::from(self.read_u16(addr::GOAL_TIME));
            self.timed_speed =
                (t > 0.0).then(|| ((target - self.joint.ref_pos).abs() / (t / 1000.0)).max(1.0));
        }
        if touched(addr::OFFSET, 2) && self.model.offset_sign_bit().is_some() {
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

    pub(super) fn torque_written(&mut self, before: u8) {
        let v = self.register(addr::TORQUE_ENABLE);
        if v == 128 {
            // Calibrate: the present position becomes the midpoint.
            if let Some(bit) = self.model.offset_sign_bit() {
                let mid = (self.model.model.resolution / 2) as i32;
                let offset = self.raw_of_pos(self.joint.pos).round() as i32 - mid;
                let raw = to_sign_magnitude(offset, bit);
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

    /// Writes the low 16 bits of `raw` at `address` in the model's byte
    /// order, into the EEPROM too when `persist` and the lock is open.
    pub(super) fn write_u16_raw(&mut self, address: u8, raw: u32, persist: bool) {
        let mut b = [0u8; 2];
        write_uint(raw, self.model.byte_order(), &mut b);
        let a = usize::from(address);
        if a + 1 < self.table.len() {
            self.table[a..a + 2].copy_from_slice(&b);
            if persist && self.lock_open() {
                self.saved[a..a + 2].copy_from_slice(&b);
            }
        }
    }
}

/// Whether the write of `len` bytes at `address` covers byte `reg`.
fn covers(address: u8, len: usize, reg: u8) -> bool {
    let a = usize::from(address);
    (a..a + len).contains(&usize::from(reg))
}
