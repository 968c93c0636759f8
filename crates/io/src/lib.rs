//! servobus-io: the two traits every servobus bus runs on, and the atomic
//! file writer every servobus output goes through.
//!
//! - [`Transport`]: the bytes of a half-duplex serial bus, with deadlines,
//!   and the two facts a bus's reply deadlines are built on, which it owns:
//!   its [`Clock`] and its baud rate (changed through it, never beside it).
//! - [`Clock`]: time, passed in, so that the same code runs in wall-clock
//!   time ([`SystemClock`]) and in virtual time ([`ManualClock`]).
//! - [`AtomicFile`] and [`write_atomic`]: an output file (log, plot,
//!   motion, calibration) is written to a temporary beside it and renamed
//!   over it when complete, so that a failed or refused run never leaves a
//!   truncated file or destroys the one that was there; [`check_output`]
//!   checks a target before a run without touching it. Only `std` is
//!   needed, so the library crates and the bindings share this one writer.
//!
//! They live in a crate of their own, below both the driver and the
//! simulator, so that each can be tested against the other: the simulator
//! implements [`Transport`] without depending on the driver, and the
//! driver's tests use the simulator as an ordinary dev-dependency. Users
//! need not name this crate for the bus: `servobus-driver` re-exports the
//! traits and clocks.
//!
//! ```text
//!   servobus-driver ──▶ servobus-io ◀── servobus-sim
//!        └─────── dev-dependency ──────────▲
//! ```
//!
//! ```
//! use std::time::Duration;
//! use servobus_io::{Clock, ManualClock};
//!
//! let clock = ManualClock::new();
//! let shared = clock.clone();
//! clock.advance(Duration::from_millis(5));
//! assert_eq!(shared.now(), Duration::from_millis(5));
//! ```
#![warn(missing_docs)]

mod atomic;
mod clock;
mod transport;

pub use atomic::{check_output, write_atomic, AtomicFile, OutputError};
pub use clock::{Clock, ManualClock, SystemClock};
pub use transport::{Transport, TransportError};
