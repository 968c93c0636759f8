//! [`Bus`]: transactions with the servos of one serial bus.
//!
//! The bus itself and its accessors are here; the single-servo requests,
//! the transaction that runs them (retries, counters) and the latency
//! measurement each have a module.

mod broadcast;
mod late;
mod latency;
mod requests;
mod transact;

use std::time::Duration;

use servobus_protocol::{BROADCAST_ID, MAX_PARAMS};
use servobus_timing::{Link, Transaction};

pub use latency::{LatencyMeasurement, PROBE_CEILING, PROBE_PINGS};
pub(crate) use transact::Expect;

use crate::io::Io;
use crate::settings::BusSettings;
use crate::stats::BusCounters;
use crate::sync::SyncStore;
use crate::{BusError, Transport, TransportError};

/// A client for one bus of Feetech servos over a [`Transport`], with time
/// from the transport's [`Clock`](crate::Clock) (`T::Clock`).
///
/// Every transaction drains stale input, sends its request, skips the echo
/// of it, and waits for the reply until a deadline derived from the
/// [`BusSettings::link`] (never a fixed timeout). Failed transactions are
/// tried again up to [`BusSettings::retries`] times; everything is counted
/// (see [`Bus::counters`] and [`Bus::servo_counters`]).
///
/// The bus owns its buffers: after construction, [`Bus::sync_write`] never
/// allocates and [`Bus::sync_read`] does not either (its result storage
/// grows only when a call needs more room than any earlier one).
pub struct Bus<T: Transport> {
    pub(crate) io: Io<T>,
    pub(crate) settings: BusSettings,
    /// Data of the last single-servo reply.
    pub(crate) reply: [u8; MAX_PARAMS],
    pub(crate) reply_len: usize,
    /// Round trip of the last successful single-servo transaction.
    pub(crate) last_rtt: Duration,
    pub(crate) counters: BusCounters,
    pub(crate) servos: Box<[BusCounters; 256]>,
    pub(crate) sync: SyncStore,
}

impl<T: Transport> std::fmt::Debug for Bus<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Bus")
            .field("settings", &self.settings)
            .field("counters", &self.counters)
            .finish_non_exhaustive()
    }
}

impl<T: Transport> Bus<T> {
    /// A bus over `transport`, with `settings` for everything else.
    ///
    /// The transport owns the clock and the baud rate: the bus times its
    /// deadlines on [`Transport::clock`] and derives them at
    /// [`Transport::baud`] ([`Bus::link`]: the settings' delays at that
    /// rate). Change the rate with
    /// [`Bus::set_baud`], which moves the transport and the deadlines
    /// together.
    pub fn new(transport: T, settings: BusSettings) -> Self {
        let mut io = Io::new(transport);
        io.echo = settings.echo;
        Bus {
            io,
            settings,
            reply: [0; MAX_PARAMS],
            reply_len: 0,
            last_rtt: Duration::ZERO,
            counters: BusCounters::default(),
            servos: Box::new([BusCounters::default(); 256]),
            sync: SyncStore::new(),
        }
    }
}

impl<T: Transport> Bus<T> {
    /// The settings in use.
    pub fn settings(&self) -> &BusSettings {
        &self.settings
    }

    /// Changes the settings (e.g. the latency after [`Bus::measure_latency`],
    /// or the series once a servo's model is known). The baud rate is not
    /// one of them: it is the transport's (see [`Bus::set_baud`]), so
    /// settings saved before a switch can be put back after it.
    pub fn set_settings(&mut self, settings: BusSettings) {
        self.io.echo = settings.echo;
        self.settings = settings;
    }

    /// The baud rate in use (the transport's).
    pub fn baud(&self) -> u32 {
        self.io.transport.baud()
    }

    /// The link every deadline is derived from: the settings' delays at
    /// the transport's baud rate.
    pub fn link(&self) -> Link {
        self.settings.link.at(self.io.transport.baud())
    }

    /// Moves the transport to `baud` and derives every deadline from then
    /// on at that rate: the one way to change a bus's rate. Nothing happens
    /// when the bus is already at `baud`.
    ///
    /// # Errors
    /// [`BusError::Transport`] when the transport refuses the rate (a rate
    /// of 0, a port that cannot run at it); the bus stays at its rate.
    pub fn set_baud(&mut self, baud: u32) -> Result<(), BusError> {
        let current = self.io.transport.baud();
        if baud == current {
            return Ok(());
        }
        if baud == 0 {
            return Err(BusError::Transport(TransportError::BaudRefused {
                requested: baud,
                current,
            }));
        }
        self.io.transport.set_baud(baud)?;
        Ok(())
    }

    /// When a request sent now starts on the wire: now, or once the
    /// requests already written are through the transmitter (a write
    /// returns once its bytes are queued). Reply deadlines count from
    /// there; so should any measurement of a reply's round trip.
    pub fn line_free(&self) -> Duration {
        self.io.next_start()
    }

    /// When the servos had heard the whole of the last request sent (its
    /// start on the wire plus its wire time): the time a reply to it
    /// describes, however late the host read the reply.
    pub fn heard(&self) -> Duration {
        self.io.heard()
    }

    /// Sets the adapter latency used in every deadline.
    pub fn set_latency(&mut self, latency: Duration) {
        self.settings.link.latency = latency;
    }

    /// The transport.
    pub fn transport(&self) -> &T {
        &self.io.transport
    }

    /// The transport, mutably (e.g. to turn busy polling on). Change its
    /// baud rate with [`Bus::set_baud`], not here.
    pub fn transport_mut(&mut self) -> &mut T {
        &mut self.io.transport
    }

    /// The transport's clock, on which the bus times its deadlines.
    pub fn clock(&self) -> &T::Clock {
        self.io.transport.clock()
    }

    /// Gives the transport back (its clock with it).
    pub fn into_transport(self) -> T {
        self.io.transport
    }

    /// Counters of the whole bus.
    pub fn counters(&self) -> &BusCounters {
        &self.counters
    }

    /// Counters of servo `id` (broadcast requests are counted under 254).
    pub fn servo_counters(&self, id: u8) -> &BusCounters {
        &self.servos[usize::from(id)]
    }

    /// Sets every counter back to zero.
    pub fn reset_counters(&mut self) {
        self.counters = BusCounters::default();
        self.servos.fill(BusCounters::default());
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
        self.link().deadline(tx, s.return_delay, s.replies)
    }

    /// What a request to `id` waits for: the reply of `len` data bytes to
    /// `tx` (accepted from `alt` too), or nothing.
    pub(crate) fn expect(&self, id: u8, alt: u8, len: usize, tx: Transaction) -> Expect {
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
    pub(crate) fn expect_reply(
        &self,
        id: u8,
        len: usize,
        tx: Transaction,
    ) -> Result<Expect, BusError> {
        let expect = self.expect(id, id, len, tx);
        if expect.reply {
            Ok(expect)
        } else {
            Err(BusError::NotAnswered {
                level: self.settings.replies,
            })
        }
    }
}
