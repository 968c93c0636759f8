//! [`Servos`]: registers by name and typed values, for programs that talk to
//! servos directly.
//!
//! [`Bus`] speaks in addresses and bytes, which is what a control loop that
//! packs its own frames wants. A program that just wants to read where six
//! servos are and send them somewhere else should not compute a block
//! length, a byte order or a sign bit: [`Servos`] takes the typed register
//! constants of [`sts`](crate::registers::sts) and
//! [`scs`](crate::registers::scs) and gives back Rust values, one result per
//! servo.

use servobus_protocol::registers::{Reg, RegisterValue, ValueError};
use servobus_protocol::StatusFlags;

use servobus_protocol::registers::{addr, model_by_register, ByteOrder, Model};
use servobus_protocol::MAX_ID;

use crate::{Bus, BusError, EepromWrite, Missing, MissingReason, SyncRead, Transport};
#[cfg(feature = "serial")]
use crate::{BusSettings, Clock};

/// A bus of servos, read and written through typed registers.
///
/// ```
/// use std::time::Duration;
/// use servobus_driver::registers::sts;
/// use servobus_driver::{Bus, BusSettings, Clock, ManualClock, Series, Servos};
/// use servobus_sim::{SimBus, SimServo};
///
/// // Two simulated STS3215 as they leave the factory (return delay 500 us),
/// // in virtual time. A real program calls `Servos::open(port, baud)`.
/// let clock = ManualClock::new();
/// let sim = SimBus::new(clock.clone(), 1_000_000).with_servos((1..=2).map(SimServo::sts3215));
/// let settings = BusSettings::new(Series::Sts)
///     .with_return_delay(servobus_driver::registers::FACTORY_RETURN_DELAY);
/// let mut servos = Servos::new(Bus::new(sim, settings));
///
/// servos.write(1, sts::TORQUE_ENABLE, 1)?;
/// servos.write(2, sts::TORQUE_ENABLE, 1)?;
/// servos.sync_write(sts::GOAL_POSITION, &[(1, 1000), (2, 3000)])?;
/// let later = servos.clock().now() + Duration::from_secs(2);
/// servos.clock().sleep_until(later);
///
/// let positions = servos.sync_read(sts::PRESENT_POSITION, &[1, 2])?;
/// let steps: Vec<i16> = positions.into_iter().map(|p| p.unwrap()).collect();
/// assert!((steps[0] - 1000).abs() <= 2 && (steps[1] - 3000).abs() <= 2);
/// # Ok::<(), servobus_driver::BusError>(())
/// ```
pub struct Servos<T: Transport> {
    bus: Bus<T>,
    /// Reused SYNC WRITE arguments.
    ids: Vec<u8>,
    data: Vec<u8>,
}

impl<T: Transport> std::fmt::Debug for Servos<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Servos").field("bus", &self.bus).finish()
    }
}

#[cfg(feature = "serial")]
impl Servos<crate::SerialTransport<crate::SystemClock>> {
    /// Opens the serial port `path` at `baud` on the system clock, with the
    /// default settings of [`BusSettings::new`] and the latency the port
    /// calls for
    /// ([`SerialTransport::assumed_latency`](crate::SerialTransport::assumed_latency)),
    /// and finds out what servos are on it ([`Servos::detect`]): STS/SMS
    /// (the SO-100/SO-101 arms' STS3215) or SCS. Use
    /// [`Servos::open_series`] when the series is known, or when no servo
    /// is powered yet.
    ///
    /// # Errors
    /// [`BusError::Transport`] when the port cannot be opened; as
    /// [`Servos::detect`] when no servo answers or its model is unknown.
    pub fn open(path: &str, baud: u32) -> Result<Self, BusError> {
        let mut servos = Self::open_series(path, baud, crate::Series::Sts)?;
        servos.detect()?;
        Ok(servos)
    }

    /// Opens the serial port `path` at `baud` for servos of `series`, as
    /// [`Servos::open`] does but without asking any servo.
    ///
    /// # Errors
    /// [`BusError::Transport`] when the port cannot be opened.
    pub fn open_series(path: &str, baud: u32, series: crate::Series) -> Result<Self, BusError> {
        let transport = crate::SerialTransport::open(path, baud, crate::SystemClock::new())?;
        let settings = BusSettings::new(series).with_latency(transport.assumed_latency());
        Ok(Servos::new(Bus::new(transport, settings)))
    }
}

#[cfg(feature = "serial")]
impl<C: Clock> Servos<crate::SerialTransport<C>> {
    /// Opens the serial port `path` at `baud`, timed by `clock`, with
    /// `settings`: each fact given once (the rate and the clock go to the
    /// port, the settings carry the rest).
    ///
    /// # Errors
    /// [`BusError::Transport`] when the port cannot be opened.
    pub fn open_with(
        path: &str,
        baud: u32,
        settings: BusSettings,
        clock: C,
    ) -> Result<Self, BusError> {
        let transport = crate::SerialTransport::open(path, baud, clock)?;
        Ok(Servos::new(Bus::new(transport, settings)))
    }
}

impl<T: Transport> Servos<T> {
    /// Typed access to `bus`.
    pub fn new(bus: Bus<T>) -> Self {
        Servos {
            bus,
            ids: Vec::new(),
            data: Vec::new(),
        }
    }

    /// The byte-level bus underneath (counters, settings, raw frames).
    pub fn bus(&self) -> &Bus<T> {
        &self.bus
    }

    /// The byte-level bus underneath, mutably.
    pub fn bus_mut(&mut self) -> &mut Bus<T> {
        &mut self.bus
    }

    /// Gives the byte-level bus back.
    pub fn into_bus(self) -> Bus<T> {
        self.bus
    }

    /// The clock the bus is timed by (to wait between commands).
    pub fn clock(&self) -> &T::Clock {
        self.bus.clock()
    }

    /// PING servo `id`: its status flags when it is there.
    ///
    /// # Errors
    /// As [`Bus::ping`].
    pub fn ping(&mut self, id: u8) -> Result<StatusFlags, BusError> {
        self.bus.ping(id)
    }

    /// Reads `reg` of servo `id`.
    ///
    /// # Errors
    /// [`BusError::WrongSeries`] for a register of another series than the
    /// bus's; otherwise as [`Bus::read`].
    pub fn read<V: RegisterValue>(&mut self, id: u8, reg: Reg<V>) -> Result<V, BusError> {
        self.check_series(&reg)?;
        let mut bytes = [0u8; 2];
        let bytes = &mut bytes[..usize::from(reg.size)];
        self.bus.read(id, reg.address, bytes)?;
        Ok(reg.decode_value(bytes, self.bus.settings().series.byte_order())?)
    }

    /// Writes `value` to `reg` of servo `id` (or of every servo, with the
    /// broadcast ID) with a plain WRITE. An EEPROM register written this way
    /// keeps the value until the next power cycle only: use
    /// [`Servos::save`] to make it persist.
    ///
    /// # Errors
    /// [`BusError::Value`] for a value that does not fit (an offset beyond
    /// +-2047), [`BusError::ReadOnly`] for a read-only register,
    /// [`BusError::WrongSeries`] for one of another series; otherwise as
    /// [`Bus::write`].
    pub fn write<V: RegisterValue>(
        &mut self,
        id: u8,
        reg: Reg<V>,
        value: V,
    ) -> Result<(), BusError> {
        let bytes = self.encode_one(&reg, value)?;
        self.bus
            .write(id, reg.address, &bytes[..usize::from(reg.size)])?;
        Ok(())
    }

    /// Writes `value` to the EEPROM register `reg` of servo `id` so that it
    /// survives a power cycle: unlock, write, read back, lock
    /// ([`Bus::write_eeprom`]).
    ///
    /// # Errors
    /// As [`Servos::write`] and [`Bus::write_eeprom`].
    pub fn save<V: RegisterValue>(
        &mut self,
        id: u8,
        reg: Reg<V>,
        value: V,
    ) -> Result<EepromWrite, BusError> {
        let bytes = self.encode_one(&reg, value)?;
        self.bus
            .write_eeprom(id, reg.address, &bytes[..usize::from(reg.size)])
    }

    /// Reads `reg` of every servo in `ids` (one SYNC READ; one READ each on
    /// SCS servos). One result per servo, in the order of `ids`: the value,
    /// or why the servo is missing. Status flags of the replies are in
    /// [`Bus::last_sync_read`]. A control loop that must not allocate uses
    /// [`Servos::sync_read_into`].
    ///
    /// # Errors
    /// Only for the request as a whole, as [`Bus::sync_read`].
    pub fn sync_read<V: RegisterValue>(
        &mut self,
        reg: Reg<V>,
        ids: &[u8],
    ) -> Result<Vec<Result<V, Missing>>, BusError> {
        self.check_series(&reg)?;
        let order = self.bus.settings().series.byte_order();
        let read = self.bus.sync_read(reg.address, reg.size, ids)?;
        Ok(typed(read, reg, order).collect())
    }

    /// As [`Servos::sync_read`], into `out` (one result per servo of `ids`,
    /// in their order) instead of a new vector: no call allocates (the
    /// counting-allocator test holds it from the first call).
    ///
    /// ```
    /// # use std::time::Duration;
    /// # use servobus_driver::registers::sts;
    /// # use servobus_driver::{Bus, BusSettings, Missing, Series, Servos};
    /// # use servobus_sim::{SimBus, SimServo};
    /// # let sim = SimBus::new(servobus_driver::ManualClock::new(), 1_000_000)
    /// #     .with_servos((1..=3).map(|id| SimServo::sts3215(id).with_position(2000)));
    /// # let mut servos = Servos::new(Bus::new(sim, BusSettings::new(Series::Sts)
    /// #     .with_return_delay(servobus_driver::registers::FACTORY_RETURN_DELAY)));
    /// let ids = [1, 2, 3];
    /// let mut positions: [Result<i16, Missing>; 3] = [Ok(0); 3];
    /// servos.sync_read_into(sts::PRESENT_POSITION, &ids, &mut positions)?;
    /// assert!(positions.iter().all(|p| p.is_ok_and(|steps| (steps - 2000).abs() <= 2)));
    /// # Ok::<(), servobus_driver::BusError>(())
    /// ```
    ///
    /// # Errors
    /// [`BusError::BufferLength`] when `out` does not hold one result per
    /// servo (nothing is sent); otherwise as [`Servos::sync_read`]. On an
    /// error `out` is unchanged.
    pub fn sync_read_into<V: RegisterValue>(
        &mut self,
        reg: Reg<V>,
        ids: &[u8],
        out: &mut [Result<V, Missing>],
    ) -> Result<(), BusError> {
        if out.len() != ids.len() {
            return Err(BusError::BufferLength {
                expected: ids.len(),
                actual: out.len(),
            });
        }
        self.check_series(&reg)?;
        let order = self.bus.settings().series.byte_order();
        let read = self.bus.sync_read(reg.address, reg.size, ids)?;
        for (slot, result) in out.iter_mut().zip(typed(read, reg, order)) {
            *slot = result;
        }
        Ok(())
    }

    /// Asks servo `id` what it is (one read of its model-number register,
    /// address 3 in both series: a servo that is not there is silent to it
    /// as to a PING, so no PING goes first) and switches the bus to the
    /// model's series, so that the registers of [`sts`](crate::registers::sts)
    /// or [`scs`](crate::registers::scs) read right from then on.
    ///
    /// # Errors
    /// [`BusError::UnknownModel`] when the number is no known model (the
    /// series is unchanged); as [`Bus::read`].
    pub fn detect_series(&mut self, id: u8) -> Result<&'static Model, BusError> {
        let mut number = [0u8; 2];
        self.bus.read(id, addr::MODEL_NUMBER, &mut number)?;
        let model = model_by_register(number).ok_or(BusError::UnknownModel {
            id,
            number: u16::from_le_bytes(number),
        })?;
        let settings = self.bus.settings().with_series(model.series);
        self.bus.set_settings(settings);
        Ok(model)
    }

    /// Finds the servo with the lowest ID that answers a PING (IDs 0 to
    /// 253, in order) and switches the bus to its series
    /// ([`Servos::detect_series`]). Returns its ID and model. A bus of
    /// servos of one series, the usual case, is then read right whichever
    /// servo is asked.
    ///
    /// # Errors
    /// [`BusError::NoServo`] when no ID answers; as
    /// [`Servos::detect_series`] for the servo found; a failing transport.
    pub fn detect(&mut self) -> Result<(u8, &'static Model), BusError> {
        for id in 0..=MAX_ID {
            match self.detect_series(id) {
                Ok(model) => return Ok((id, model)),
                // Silence, or a garbled or misrouted reply: not this ID.
                Err(e) if e.is_retryable() => {}
                Err(e) => return Err(e),
            }
        }
        Err(BusError::NoServo {
            baud: self.bus.baud(),
        })
    }

    /// Writes one value of `reg` to each servo in one SYNC WRITE: `values`
    /// pairs an ID with its value, so every servo gets exactly one value of
    /// the register's width. Nobody answers.
    ///
    /// # Errors
    /// [`BusError::Value`] when a value does not fit (nothing is sent),
    /// [`BusError::DuplicateId`] for an ID given twice,
    /// [`BusError::ReadOnly`] or [`BusError::WrongSeries`] for the register,
    /// [`BusError::InvalidRequest`] for no values; otherwise as
    /// [`Bus::sync_write`].
    pub fn sync_write<V: RegisterValue>(
        &mut self,
        reg: Reg<V>,
        values: &[(u8, V)],
    ) -> Result<(), BusError> {
        self.check_writable(&reg)?;
        let order = self.bus.settings().series.byte_order();
        let size = usize::from(reg.size);
        self.ids.clear();
        self.data.clear();
        let mut seen = [false; 256];
        for &(id, value) in values {
            if std::mem::replace(&mut seen[usize::from(id)], true) {
                return Err(BusError::DuplicateId { id });
            }
            self.ids.push(id);
            let at = self.data.len();
            self.data.resize(at + size, 0);
            reg.encode_value(value, order, &mut self.data[at..])?;
        }
        self.bus.sync_write(reg.address, &self.ids, &self.data)
    }

    /// The bytes of `value` in `reg`, checked writable and of this series.
    fn encode_one<V: RegisterValue>(&self, reg: &Reg<V>, value: V) -> Result<[u8; 2], BusError> {
        self.check_writable(reg)?;
        let mut bytes = [0u8; 2];
        let order = self.bus.settings().series.byte_order();
        reg.encode_value(value, order, &mut bytes[..usize::from(reg.size)])?;
        Ok(bytes)
    }

    fn check_writable<V>(&self, reg: &Reg<V>) -> Result<(), BusError> {
        self.check_series(reg)?;
        if reg.access.is_writable() {
            Ok(())
        } else {
            Err(BusError::ReadOnly {
                address: reg.address,
            })
        }
    }

    /// Refuses a register the bus's series does not have at that address
    /// with that layout (e.g. `sts::PRESENT_POSITION`, signed, on SCS servos,
    /// whose position is unsigned).
    fn check_series<V>(&self, reg: &Reg<V>) -> Result<(), BusError> {
        let map = self.bus.settings().series.map();
        match map.at(reg.address) {
            Some(r) if r.size == reg.size && r.sign_bit == reg.sign_bit => Ok(()),
            _ => Err(BusError::WrongSeries {
                address: reg.address,
                series: self.bus.settings().series,
            }),
        }
    }
}

/// The results of `read` as values of `reg`: a reply whose bytes do not
/// decode counts as one of the wrong length.
fn typed<'a, V: RegisterValue + 'a>(
    read: SyncRead<'a>,
    reg: Reg<V>,
    order: ByteOrder,
) -> impl Iterator<Item = Result<V, Missing>> + 'a {
    read.iter().map(move |result| {
        let reply = result?;
        reg.decode_value(reply.data, order).map_err(|_| Missing {
            id: reply.id,
            reason: MissingReason::WrongLength,
            attempts: 1,
        })
    })
}

impl From<ValueError> for BusError {
    fn from(e: ValueError) -> Self {
        BusError::Value(e)
    }
}
