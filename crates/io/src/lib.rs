//! servobus-io: the two traits every servobus bus runs on.
//!
//! - [`Transport`]: the bytes of a half-duplex serial bus, with deadlines.
//! - [`Clock`]: time, passed in, so that the same code runs in wall-clock
//!   time ([`SystemClock`]) and in virtual time ([`ManualClock`]).
//!
//! They live in a crate of their own, below both the driver and the
//! simulator, so that each can be tested against the other: the simulator
//! implements [`Transport`] without depending on the driver, and the
//! driver's tests use the simulator as an ordinary dev-dependency. Users
//! need not name this crate: `servobus-driver` re-exports everything here.
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

mod clock;
mod transport;

pub use clock::{Clock, ManualClock, SystemClock};
pub use transport::{Transport, TransportError};
