//! The single-servo requests: PING, READ, WRITE and its kin, and registers
//! read and written by name.

use servobus_protocol::registers::{Access, Register};
use servobus_protocol::{encode, Command, StatusFlags, BROADCAST_ID};
use servobus_timing::Transaction;

use crate::{Bus, BusError, Transport};

impl<T: Transport> Bus<T> {
    /// PING servo `id`: whether it is there, and its status flags.
    ///
    /// # Errors
    /// [`BusError::Timeout`] when nobody answers, [`BusError::Corrupt`] on a
    /// garbled reply (two servos sharing the ID look like this), and the
    /// other [`BusError`]s.
    pub fn ping(&mut self, id: u8) -> Result<StatusFlags, BusError> {
        if id == BROADCAST_ID {
            return Err(BusError::InvalidRequest(
                "a broadcast PING is answered by every servo at once",
            ));
        }
        let expect = self.expect_reply(id, 0, Transaction::Ping)?;
        self.io.begin();
        self.io.tx_len = encode::ping(&mut self.io.tx, id)?;
        // A servo whose status is exactly 0x01 (the voltage flag) answers a
        // PING with the PING's own bytes: the transaction tells that reply
        // from an echo (see `Bus::port_echoes`).
        Ok(self.transact(expect)?.unwrap_or_default())
    }

    /// READ `out.len()` bytes from `address` of servo `id` into `out`.
    /// Returns the reply's status flags.
    ///
    /// # Errors
    /// As [`Bus::ping`]; [`BusError::InvalidRequest`] for an empty `out` or
    /// more than 255 bytes.
    pub fn read(&mut self, id: u8, address: u8, out: &mut [u8]) -> Result<StatusFlags, BusError> {
        let len = u8::try_from(out.len())
            .map_err(|_| BusError::InvalidRequest("a READ returns at most 255 bytes"))?;
        let expect = self.expect_reply(id, out.len(), Transaction::Read { len: out.len() })?;
        self.io.begin();
        self.io.tx_len = encode::read(&mut self.io.tx, id, address, len)?;
        let flags = self.transact(expect)?.unwrap_or_default();
        out.copy_from_slice(&self.reply[..out.len()]);
        Ok(flags)
    }

    /// WRITE `data` at `address` of servo `id` (or of every servo, with the
    /// broadcast ID). Returns the reply's status flags, or `None` when no
    /// reply is expected (broadcast, or a [`StatusLevel`](crate::StatusLevel)
    /// that does not answer writes).
    ///
    /// Writing an EEPROM register this way changes it until the next power
    /// cycle only (unless the lock is open): use [`Bus::write_eeprom`] to make
    /// it persist.
    ///
    /// # Errors
    /// As [`Bus::ping`].
    pub fn write(
        &mut self,
        id: u8,
        address: u8,
        data: &[u8],
    ) -> Result<Option<StatusFlags>, BusError> {
        self.write_either(id, id, address, data)
    }

    /// WRITE accepting the reply from `id` or from `alt` (the new ID, when
    /// the ID register itself is written).
    pub(crate) fn write_either(
        &mut self,
        id: u8,
        alt: u8,
        address: u8,
        data: &[u8],
    ) -> Result<Option<StatusFlags>, BusError> {
        self.request(id, alt, Command::Write { address, data })
    }

    /// REG WRITE `data` at `address` of servo `id`: held by the servo until
    /// [`Bus::action`]. Returns as [`Bus::write`].
    ///
    /// # Errors
    /// As [`Bus::ping`].
    pub fn reg_write(
        &mut self,
        id: u8,
        address: u8,
        data: &[u8],
    ) -> Result<Option<StatusFlags>, BusError> {
        self.request(id, id, Command::RegWrite { address, data })
    }

    /// ACTION: servos holding REG WRITE data apply it. Usually broadcast
    /// (no reply); addressed to one servo it is answered as a WRITE.
    ///
    /// # Errors
    /// As [`Bus::ping`].
    pub fn action(&mut self, id: u8) -> Result<Option<StatusFlags>, BusError> {
        self.request(id, id, Command::Action)
    }

    /// RESET servo `id` to factory values (its ID included, on most
    /// firmware). Returns as [`Bus::write`].
    ///
    /// # Errors
    /// As [`Bus::ping`].
    pub fn reset(&mut self, id: u8) -> Result<Option<StatusFlags>, BusError> {
        self.request(id, id, Command::Reset)
    }

    /// Sends `command`, one of the requests answered as a WRITE is (with no
    /// data, by `id` or `alt`, or not at all).
    fn request(
        &mut self,
        id: u8,
        alt: u8,
        command: Command<'_>,
    ) -> Result<Option<StatusFlags>, BusError> {
        let tx = match command {
            Command::Write { data, .. } => Transaction::Write { len: data.len() },
            Command::RegWrite { data, .. } => Transaction::RegWrite { len: data.len() },
            Command::Action => Transaction::Action,
            Command::Reset => Transaction::Reset,
            _ => return Err(BusError::InvalidRequest("not a WRITE-like request")),
        };
        self.io.begin();
        self.io.tx_len = encode::command(&mut self.io.tx, id, &command)?;
        let expect = self.expect(id, alt, 0, tx);
        self.transact(expect)
    }

    /// Reads one register and decodes it with this bus's byte order.
    /// Returns the value and the status flags.
    ///
    /// # Errors
    /// As [`Bus::read`]; [`BusError::InvalidRequest`] for a register wider
    /// than 4 bytes.
    pub fn read_register(
        &mut self,
        id: u8,
        register: &Register,
    ) -> Result<(i32, StatusFlags), BusError> {
        let mut buf = [0u8; 4];
        let bytes = buf
            .get_mut(..usize::from(register.size))
            .ok_or(BusError::InvalidRequest("register wider than 4 bytes"))?;
        let flags = self.read(id, register.address, bytes)?;
        let value = register
            .decode(bytes, self.settings.series.byte_order())
            .map_err(BusError::Value)?;
        Ok((value, flags))
    }

    /// Writes one register, encoded with this bus's byte order. An EEPROM
    /// register is written with the persistent transaction of
    /// [`Bus::write_eeprom`]; a RAM register with a plain WRITE.
    ///
    /// # Errors
    /// [`BusError::ReadOnly`] for a read-only register, [`BusError::Value`]
    /// for a value that does not fit; otherwise as [`Bus::write`] / [`Bus::write_eeprom`].
    pub fn write_register(
        &mut self,
        id: u8,
        register: &Register,
        value: i32,
    ) -> Result<Option<StatusFlags>, BusError> {
        let mut buf = [0u8; 4];
        let bytes = buf
            .get_mut(..usize::from(register.size))
            .ok_or(BusError::InvalidRequest("register wider than 4 bytes"))?;
        register
            .encode(value, self.settings.series.byte_order(), bytes)
            .map_err(BusError::Value)?;
        let bytes = &buf[..usize::from(register.size)];
        match register.access {
            Access::ReadOnly => Err(BusError::ReadOnly {
                address: register.address,
            }),
            Access::Ram => self.write(id, register.address, bytes),
            Access::Eeprom => self
                .write_eeprom(id, register.address, bytes)
                .map(|w| Some(w.flags)),
        }
    }
}
