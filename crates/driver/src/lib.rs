//! servobus-driver: talk to a bus of Feetech servos through any
//! [`Transport`], with time passed in through a [`Clock`].
//!
//! A [`Bus`] does the transactions of the Feetech protocol — PING, READ,
//! WRITE, REG WRITE + ACTION, SYNC WRITE, SYNC READ, RESET — and the
//! persistent EEPROM write (unlock, write, verify, lock). Why it is built
//! the way it is:
//!
//! - **Deadlines are derived, never fixed.** Each reply deadline is the wire
//!   time of request and reply at the baud rate, the servo's return delay,
//!   the adapter's latency and a margin ([`servobus_timing::Link`]). At
//!   1 Mbps with a 1 ms adapter a READ waits about 1.4 ms, not the tens of
//!   milliseconds generic SDKs wait, so a lost reply can be re-asked within
//!   the same control cycle.
//! - **Results per servo.** A SYNC READ keeps every answer that came and says
//!   why each missing servo is missing; it never fails because one servo was
//!   silent, and never attributes a reply to the wrong servo.
//! - **Time and bytes are passed in.** The transport is a trait with
//!   deadlines and the clock is a trait, so the same code runs on a real
//!   serial port ([`SerialTransport`], feature `serial`) and on the simulator
//!   in virtual time, deterministically.
//! - **No allocation on the hot path.** Frames are encoded into buffers the
//!   bus owns; SYNC READ results live in reused storage.
//!
//! ```text
//!  host                                   servos 1, 2, 3
//!  |-- SYNC WRITE (broadcast, no reply) --->|
//!  |-- SYNC READ 1,2,3 -------------------->|
//!  |<----------------- reply 1 -------------|  each after its return delay,
//!  |<----------------- reply 2 -------------|  in request order
//!  |<----------------- reply 3 -------------|
//!  deadline = wire(request) + n x (return delay + turnaround)
//!             + wire(replies) + adapter latency + margin
//! ```
//!
//! # Reading and writing servos from your own program
//!
//! [`Servos`] is the typed API: open a port in one call, then read and write
//! registers by their constants in [`registers::sts`] (STS/SMS) or
//! [`registers::scs`] (SCS), as Rust values with the sign handled, one
//! result per servo:
//!
//! ```no_run
//! use servobus_driver::{registers::sts, Servos};
//!
//! let mut servos = Servos::open("/dev/ttyACM0", 1_000_000)?;
//! let ids = [1, 2, 3, 4, 5, 6];
//! for (id, position) in ids.iter().zip(servos.sync_read(sts::PRESENT_POSITION, &ids)?) {
//!     match position {
//!         Ok(steps) => println!("servo {id} is at {steps} steps"), // an i16
//!         Err(missing) => println!("servo {id} is missing: {}", missing.reason),
//!     }
//! }
//! // One (id, value) pair per servo: no block length to get wrong.
//! servos.sync_write(sts::GOAL_POSITION, &[(1, 2048), (2, 1024)])?;
//! # Ok::<(), servobus_driver::BusError>(())
//! ```
//!
//! [`Servos::open`] finds out which servos are on the port (a PING and a
//! read of the model number of the first servo that answers) and reads
//! STS/SMS or SCS registers accordingly; [`Servos::open_series`] takes the
//! series instead. [`Servos::sync_read_into`] fills a buffer of the
//! caller's, so a control loop reads without allocating.
//!
//! The example `positions` does this on a real port (`--port`) or on
//! simulated servos (`--sim`):
//! `cargo run -p servobus-driver --example positions -- --sim --nudge 100`.
//!
//! # The byte-level bus
//!
//! A [`Bus`] is built from a [`Transport`] and [`BusSettings`], each fact
//! once: the transport owns the clock its deadlines are measured on and
//! the baud rate (a [`SerialTransport`] is opened at a rate on a clock, the
//! simulator's bus is made at one on its [`ManualClock`]); the settings
//! carry the rest (series, latency, return delay, retries).
//! [`Bus::set_baud`] is the one way to change the rate: it moves the port
//! and every deadline together.
//!
//! A bus over a transport that answers like one servo with ID 1 (a real
//! program would use [`SerialTransport`] on a [`SystemClock`], or the
//! simulator's bus):
//!
//! ```
//! use std::time::Duration;
//! use servobus_driver::{Bus, BusSettings, ManualClock, Transport, TransportError};
//! use servobus_protocol::{encode, parse_frame, registers::Series, StatusFlags};
//!
//! /// Answers every READ of servo 1 with the bytes 0x00 0x08 (2048), at
//! /// 1 Mbps, with deadlines on `clock`.
//! struct OneServo { pending: Vec<u8>, clock: ManualClock }
//! impl Transport for OneServo {
//!     type Clock = ManualClock;
//!     fn clock(&self) -> &ManualClock { &self.clock }
//!     fn baud(&self) -> u32 { 1_000_000 }
//!     fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
//!         if let Ok((p, _)) = parse_frame(bytes) {
//!             let mut buf = [0u8; 16];
//!             let n = encode::status(&mut buf, 1, StatusFlags(0), &[0x00, 0x08]).unwrap();
//!             if p.id() == 1 { self.pending.extend_from_slice(&buf[..n]); }
//!         }
//!         Ok(())
//!     }
//!     fn read(&mut self, buf: &mut [u8], _deadline: Duration) -> Result<usize, TransportError> {
//!         if self.pending.is_empty() { return Err(TransportError::TimedOut); }
//!         let n = buf.len().min(self.pending.len());
//!         buf[..n].copy_from_slice(&self.pending[..n]);
//!         self.pending.drain(..n);
//!         Ok(n)
//!     }
//!     fn discard_input(&mut self) -> Result<(), TransportError> {
//!         self.pending.clear();
//!         Ok(())
//!     }
//! }
//!
//! let settings = BusSettings::new(Series::Sts).with_latency(Duration::from_millis(1));
//! // The clock and the baud rate come from the transport; the settings
//! // carry the rest.
//! let mut bus = Bus::new(OneServo { pending: Vec::new(), clock: ManualClock::new() }, settings);
//! let mut position = [0u8; 2];
//! let flags = bus.read(1, 56, &mut position)?;
//! assert!(flags.is_ok());
//! assert_eq!(u16::from_le_bytes(position), 2048);
//! // Servo 2 is absent: a typed timeout, after a deadline derived from the link.
//! let err = bus.read(2, 56, &mut position).unwrap_err();
//! assert!(err.is_timeout());
//! assert_eq!(bus.counters().timeouts, 2); // the first try and one retry
//! # Ok::<(), servobus_driver::BusError>(())
//! ```
#![warn(missing_docs)]

mod bus;
mod eeprom;
mod error;
mod io;
pub mod scripted;
#[cfg(feature = "serial")]
mod serial;
mod servos;
mod settings;
pub mod signals;
mod stats;
mod sync;
#[cfg(test)]
mod testing;

pub use bus::{Bus, LatencyMeasurement, PROBE_CEILING, PROBE_PINGS};
pub use eeprom::EepromWrite;
pub use error::BusError;
#[cfg(feature = "serial")]
pub use serial::{
    ftdi_latency_timer, FtdiLatency, Holder, NotSerial, OpenError, OpenProblem, SerialTransport,
};
pub use servobus_io::{Clock, ManualClock, SystemClock, Transport, TransportError};
pub use servobus_timing::StatusLevel;
pub use servos::Servos;
pub use settings::BusSettings;
pub use signals::{catch_stop_signals, held_signal_pending, stop_signal, SignalHold, StopSignal};

/// The register maps and typed register constants ([`registers::sts`],
/// [`registers::scs`]), re-exported so that one crate is enough.
pub use servobus_protocol::registers;
pub use servobus_protocol::registers::{Reg, Series};
pub use servobus_protocol::StatusFlags;
pub use servobus_timing::Link;
pub use stats::{BusCounters, RttStats};
pub use sync::{Missing, MissingReason, SyncRead, SyncReply, PATIENCE, PATIENT_TRIES};
