//! [`Bus`]: transactions with the servos of one serial bus.

use std::time::Duration;

use servobus_protocol::registers::{Access, Register};
use servobus_protocol::{encode, frame_len, Packet, StatusFlags, BROADCAST_ID, MAX_PARAMS};

use crate::io::{Io, Sink, Tally};
use servobus_timing::Transaction;

use crate::settings::BusSettings;
use crate::stats::Counters;
use crate::sync::SyncStore;
use crate::{BusError, Clock, Transport};

/// A client for one bus of Feetech servos over a [`Transport`], with time
/// from a [`Clock`].
///
/// Every transaction drains stale input, sends its request, skips the echo
/// of it, and waits for the reply until a deadline derived from the
/// [`BusSettings::link`] (never a fixed timeout). Failed transactions are
/// tried again up to [`BusSettings::retries`] times; everything is counted
/// (see [`Bus::counters`] and [`Bus::servo_counters`]).
///
/// The bus owns its buffers: after construction, [`Bus::sync_write`] and
/// [`Bus::sync_read`] do not allocate (the SYNC READ result storage grows
/// only when a call needs more room than any earlier one).
pub struct Bus<T: Transport, C: Clock> {
    pub(crate) io: Io<T, C>,
    pub(crate) settings: BusSettings,
    /// Data of the last single-servo reply.
    reply: [u8; MAX_PARAMS],
    reply_len: usize,
    /// Round trip of the last successful single-servo transaction.
    last_rtt: Duration,
    pub(crate) counters: Counters,
    pub(crate) servos: Box<[Counters; 256]>,
    pub(crate) sync: SyncStore,
    /// SYNC WRITE frames too many for one frame, packed before sending.
    pub(crate) packed: Vec<u8>,
}

impl<T: Transport, C: Clock> std::fmt::Debug for Bus<T, C> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Bus")
            .field("settings", &self.settings)
            .field("counters", &self.counters)
            .finish_non_exhaustive()
    }
}

/// What a single-servo transaction waits for.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Expect {
    /// The servo asked; a reply from `alt` is accepted too (an ID change).
    pub id: u8,
    pub alt: u8,
    /// Data bytes the reply carries.
    pub len: usize,
    /// Whether a reply comes at all.
    pub reply: bool,
    /// Deadline from the start of sending.
    pub timeout: Duration,
}

/// Collects the reply to a single-servo request.
struct Single<'a> {
    expect: Expect,
    out: &'a mut [u8; MAX_PARAMS],
    out_len: &'a mut usize,
    /// `(flags, arrival)` once the reply came.
    got: Option<(StatusFlags, Duration)>,
    /// The first wrong reply seen, if any.
    wrong: Option<BusError>,
    wrong_count: u64,
    corrupt: bool,
}

impl Sink for Single<'_> {
    fn packet(&mut self, packet: &Packet<'_>, now: Duration) -> bool {
        let id = packet.id();
        let params = packet.params();
        let err = if id != self.expect.id && id != self.expect.alt {
            BusError::WrongId {
                expected: self.expect.id,
                actual: id,
            }
        } else if params.len() != self.expect.len {
            BusError::WrongLength {
                id,
                expected: self.expect.len,
                actual: params.len(),
            }
        } else {
            self.out[..params.len()].copy_from_slice(params);
            *self.out_len = params.len();
            self.got = Some((packet.status(), now));
            return true;
        };
        self.wrong_count += 1;
        self.wrong.get_or_insert(err);
        false
    }

    fn checksum_error(&mut self, _id: u8) {
        // The ID byte of a corrupted frame cannot be trusted: any corruption
        // in the window of a single-servo request is taken as its reply
        // (two servos with one ID collide exactly like this).
        self.corrupt = true;
    }
}

impl<T: Transport, C: Clock> Bus<T, C> {
    /// A bus over `transport`, timed by `clock`.
    pub fn new(transport: T, clock: C, settings: BusSettings) -> Self {
        let mut io = Io::new(transport, clock);
        io.echo = settings.echo;
        io.wire = settings.link;
        Bus {
            io,
            settings,
            reply: [0; MAX_PARAMS],
            reply_len: 0,
            last_rtt: Duration::ZERO,
            counters: Counters::default(),
            servos: Box::new([Counters::default(); 256]),
            sync: SyncStore::new(),
            packed: Vec::new(),
        }
    }

    /// The settings in use.
    pub fn settings(&self) -> &BusSettings {
        &self.settings
    }

    /// Changes the settings (e.g. the latency after [`Bus::measure_latency`],
    /// or the baud rate after reopening the transport).
    pub fn set_settings(&mut self, settings: BusSettings) {
        self.io.echo = settings.echo;
        self.io.wire = settings.link;
        self.settings = settings;
    }

    /// Sets the adapter latency used in every deadline.
    pub fn set_latency(&mut self, latency: Duration) {
        self.settings.link.latency = latency;
    }

    /// The transport.
    pub fn transport(&self) -> &T {
        &self.io.transport
    }

    /// The transport, mutably (e.g. to change its baud rate).
    pub fn transport_mut(&mut self) -> &mut T {
        &mut self.io.transport
    }

    /// The clock.
    pub fn clock(&self) -> &C {
        &self.io.clock
    }

    /// Gives the transport and clock back.
    pub fn into_parts(self) -> (T, C) {
        (self.io.transport, self.io.clock)
    }

    /// Counters of the whole bus.
    pub fn counters(&self) -> &Counters {
        &self.counters
    }

    /// Counters of servo `id` (broadcast requests are counted under 254).
    pub fn servo_counters(&self, id: u8) -> &Counters {
        &self.servos[usize::from(id)]
    }

    /// Sets every counter back to zero.
    pub fn reset_counters(&mut self) {
        self.counters = Counters::default();
        self.servos.fill(Counters::default());
    }

    /// The data bytes of the last single-servo reply.
    pub fn last_reply(&self) -> &[u8] {
        &self.reply[..self.reply_len]
    }

    /// Round trip of the last successful single-servo transaction.
    pub fn last_rtt(&self) -> Duration {
        self.last_rtt
    }

    /// The deadline of `tx` to servo `id`, or `None` when no reply comes
    /// (a broadcast, or a status level that does not answer `tx`).
    pub(crate) fn deadline(&self, id: u8, tx: Transaction) -> Option<Duration> {
        if id == BROADCAST_ID {
            return None;
        }
        let s = &self.settings;
        s.link.deadline(tx, s.return_delay, s.replies)
    }

    /// What a request to `id` waits for: the reply of `len` data bytes to
    /// `tx` (accepted from `alt` too), or nothing.
    fn expect(&self, id: u8, alt: u8, len: usize, tx: Transaction) -> Expect {
        let deadline = self.deadline(id, tx);
        Expect {
            id,
            alt,
            len,
            reply: deadline.is_some(),
            timeout: deadline.unwrap_or(Duration::ZERO),
        }
    }

    /// As [`Bus::expect`] for a transaction that must be answered.
    fn expect_reply(&self, id: u8, len: usize, tx: Transaction) -> Result<Expect, BusError> {
        let expect = self.expect(id, id, len, tx);
        if expect.reply {
            Ok(expect)
        } else {
            Err(BusError::InvalidRequest(
                "the servos' status level does not answer this request",
            ))
        }
    }

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
        let echoes = self.counters.echoes;
        match self.transact(expect) {
            Ok(flags) => Ok(flags.unwrap_or_default()),
            // A servo whose status is exactly 0x01 (the voltage flag) answers
            // a PING with the PING's own bytes, which were skipped as the
            // adapter's echo. Ask it something whose answer cannot look like
            // the request before calling it silent.
            Err(e) if e.is_timeout() && self.counters.echoes > echoes => {
                let mut byte = [0u8; 1];
                self.read(id, servobus_protocol::registers::addr::ID, &mut byte)
                    .map_err(|_| e)
            }
            Err(e) => Err(e),
        }
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
        self.send_write(id, alt, data.len(), |tx| {
            encode::write(tx, id, address, data)
        })
    }

    /// Sends the WRITE-like request `encode` writes (answered as a WRITE of
    /// `len` data bytes, by `id` or `alt`).
    fn send_write(
        &mut self,
        id: u8,
        alt: u8,
        len: usize,
        encode: impl FnOnce(&mut [u8]) -> Result<usize, servobus_protocol::EncodeError>,
    ) -> Result<Option<StatusFlags>, BusError> {
        self.io.begin();
        self.io.tx_len = encode(&mut self.io.tx)?;
        let expect = self.expect(id, alt, 0, Transaction::Write { len });
        self.transact(expect)
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
        self.send_write(id, id, data.len(), |tx| {
            encode::reg_write(tx, id, address, data)
        })
    }

    /// ACTION: servos holding REG WRITE data apply it. Usually broadcast
    /// (no reply); addressed to one servo it is answered as a WRITE.
    ///
    /// # Errors
    /// As [`Bus::ping`].
    pub fn action(&mut self, id: u8) -> Result<Option<StatusFlags>, BusError> {
        self.io.begin();
        self.io.tx_len = encode::action(&mut self.io.tx, id)?;
        let expect = self.expect(id, id, 0, Transaction::Action);
        self.transact(expect)
    }

    /// RESET servo `id` to factory values (its ID included, on most
    /// firmware). Returns as [`Bus::write`].
    ///
    /// # Errors
    /// As [`Bus::ping`].
    pub fn reset(&mut self, id: u8) -> Result<Option<StatusFlags>, BusError> {
        self.io.begin();
        self.io.tx_len = encode::reset(&mut self.io.tx, id)?;
        let expect = self.expect(id, id, 0, Transaction::Reset);
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
            .map_err(|_| BusError::InvalidRequest("register value cannot be decoded"))?;
        Ok((value, flags))
    }

    /// Writes one register, encoded with this bus's byte order. An EEPROM
    /// register is written with the persistent transaction of
    /// [`Bus::write_eeprom`]; a RAM register with a plain WRITE.
    ///
    /// # Errors
    /// [`BusError::InvalidRequest`] for a read-only register or a value that
    /// does not fit; otherwise as [`Bus::write`] / [`Bus::write_eeprom`].
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
            .map_err(|_| BusError::InvalidRequest("value out of the register's range"))?;
        let bytes = &buf[..usize::from(register.size)];
        match register.access {
            Access::ReadOnly => Err(BusError::InvalidRequest("register is read-only")),
            Access::Ram => self.write(id, register.address, bytes),
            Access::Eeprom => self
                .write_eeprom(id, register.address, bytes)
                .map(|w| Some(w.flags)),
        }
    }

    /// Runs one single-servo transaction whose request is in `io.tx`, with
    /// bounded retries.
    pub(crate) fn transact(&mut self, expect: Expect) -> Result<Option<StatusFlags>, BusError> {
        let id = usize::from(expect.id);
        self.counters.transactions += 1;
        self.servos[id].transactions += 1;
        let mut last = None;
        for attempt in 0..=self.settings.retries {
            if attempt > 0 {
                self.counters.retries += 1;
                self.servos[id].retries += 1;
            }
            let start = self.io.send()?;
            if !expect.reply {
                return Ok(None);
            }
            let mut sink = Single {
                expect,
                out: &mut self.reply,
                out_len: &mut self.reply_len,
                got: None,
                wrong: None,
                wrong_count: 0,
                corrupt: false,
            };
            let tally = self.io.exchange(start + expect.timeout, &mut sink)?;
            let (got, wrong, wrong_count, corrupt) =
                (sink.got, sink.wrong, sink.wrong_count, sink.corrupt);
            self.account(id, &tally, wrong_count);
            if let Some((flags, at)) = got {
                let rtt = at.saturating_sub(start);
                self.last_rtt = rtt;
                self.counters.rtt.record(rtt);
                self.servos[id].rtt.record(rtt);
                if !flags.is_ok() {
                    self.counters.status_errors += 1;
                    self.servos[id].status_errors += 1;
                    if self.settings.strict_status {
                        return Err(BusError::Status {
                            id: expect.id,
                            flags,
                        });
                    }
                }
                return Ok(Some(flags));
            }
            // Bytes that arrived but made no valid frame are a garbled reply,
            // not silence.
            let err = if corrupt || tally.garbage_bytes > 0 {
                BusError::Corrupt { id: expect.id }
            } else if let Some(wrong) = wrong {
                wrong
            } else {
                self.counters.timeouts += 1;
                self.servos[id].timeouts += 1;
                BusError::Timeout {
                    id: expect.id,
                    waited: expect.timeout,
                }
            };
            last = Some(err);
        }
        self.counters.failures += 1;
        self.servos[id].failures += 1;
        Err(last.unwrap_or(BusError::Timeout {
            id: expect.id,
            waited: expect.timeout,
        }))
    }

    /// Adds what one wait saw to the bus counters and to servo `id`'s.
    pub(crate) fn account(&mut self, id: usize, tally: &Tally, wrong: u64) {
        for c in [&mut self.counters, &mut self.servos[id]] {
            c.echoes += tally.echoes;
            c.discarded_bytes += tally.discarded_bytes;
            c.checksum_errors += tally.checksum_errors;
            c.wrong_replies += wrong;
        }
    }

    /// Measures the adapter's latency with `samples` PINGs of servo `id`:
    /// each round trip minus what the link model already accounts for (wire
    /// time both ways, return delay, turnaround). Waits up to `ceiling` of
    /// latency per PING. Does not change the settings: pass the result to
    /// [`Bus::set_latency`] (the maximum is the safe choice).
    ///
    /// # Errors
    /// [`BusError::InvalidRequest`] for zero samples; the first failed PING's
    /// error.
    pub fn measure_latency(
        &mut self,
        id: u8,
        samples: u32,
        ceiling: Duration,
    ) -> Result<LatencyMeasurement, BusError> {
        if samples == 0 {
            return Err(BusError::InvalidRequest("no samples asked for"));
        }
        let saved = self.settings;
        self.settings.link.latency = ceiling;
        self.settings.retries = 0;
        let link = self.settings.link;
        let modelled = link.wire_time(frame_len(0) * 2) + saved.return_delay + link.turnaround;
        let mut m = LatencyMeasurement {
            samples: 0,
            min: Duration::MAX,
            mean: Duration::ZERO,
            max: Duration::ZERO,
        };
        let mut total = Duration::ZERO;
        let mut result = Ok(());
        for _ in 0..samples {
            if let Err(e) = self.ping(id) {
                result = Err(e);
                break;
            }
            let latency = self.last_rtt.saturating_sub(modelled);
            m.samples += 1;
            m.min = m.min.min(latency);
            m.max = m.max.max(latency);
            total += latency;
        }
        self.settings = saved;
        result?;
        m.mean = total / m.samples;
        Ok(m)
    }
}

/// The adapter latency measured by [`Bus::measure_latency`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LatencyMeasurement {
    /// PINGs measured.
    pub samples: u32,
    /// Smallest latency seen.
    pub min: Duration,
    /// Mean latency.
    pub mean: Duration,
    /// Largest latency seen: the value to configure.
    pub max: Duration,
}
