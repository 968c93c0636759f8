//! servobus-sim: a byte-accurate simulated Feetech servo bus.
#![warn(missing_docs)]

mod bus;
mod dynamics;
mod engine;
mod faults;
pub mod pty;
pub mod model;
mod servo;

pub use bus::SimBus;
pub use engine::{baud_of_index, SimStats};
pub use faults::{FaultSpecError, Faults};
pub use model::{Area, Endian, SimModel};
pub use pty::{PtyError, PtyServer};
pub use servo::{addr, SimServo};
