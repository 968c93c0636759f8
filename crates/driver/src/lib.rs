//! servobus-driver: talk to a bus of Feetech servos through any
//! [`Transport`], with time passed in through a [`Clock`].
#![warn(missing_docs)]

mod clock;
mod transport;

pub use clock::{Clock, ManualClock, SystemClock};
pub use transport::{Transport, TransportError};
