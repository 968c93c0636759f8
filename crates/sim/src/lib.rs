//! servobus-sim: a byte-accurate simulated Feetech servo bus.
//!
//! Code that talks to Feetech servos is only as good as its tests, and real
//! servos make poor test fixtures: they are slow to set up, they drift,
//! they never drop a reply on demand. This crate simulates them at the
//! byte level, so that the same driver code runs against the simulator and
//! against hardware:
//!
//! - [`SimServo`] is one servo: its model's memory table byte for byte
//!   ([`SimModel`]: STS3215, STS3250, SM8512BL little-endian; SCS0009, SCS15
//!   big-endian), the instructions it obeys, and a joint with a motion
//!   profile, lag, dead zone, load, heat and protection flags.
//! - [`SimBus`] puts many servos on one bus and implements
//!   [`servobus_io::Transport`] in virtual time on a shared
//!   [`ManualClock`](servobus_io::ManualClock): deterministic and as fast
//!   as the CPU allows. Faults ([`Faults`]) are drawn from a seeded source.
//! - [`body`] gives a servo a joint to drive: a [`Mount`] (raw tick at the
//!   joint's zero, direction, end stops; ranges may cross the 4095/0 seam),
//!   a [`HandPath`] that moves it while its torque is off, and a [`Truth`]
//!   recorder of the physical angles.
//! - [`PtyServer`] serves a bus on a pseudo-terminal in wall-clock time, so
//!   that any program that opens a serial port (Feetech's Python SDK,
//!   LeRobot, the `servobus` commands) can talk to it (`servobus sim`).
//!
//! ```text
//!  host ──request──▶ [wire: 10 bits a byte at the baud rate]
//!                         │ every listening servo parses the frame when
//!                         ▼ its last byte has arrived
//!              servo k: return delay (reg 7) ──reply──▶ host
//!  SYNC READ:  replies one after another in the request's ID order;
//!  same ID:    replies overlap and collide (wired-AND of the bytes)
//! ```
//!
//! # How the simulated servo behaves
//!
//! - Unicast instructions are answered as the status level (register 8)
//!   allows: STS level 0 answers PING and READ only, level 1 everything; SCS
//!   level 0 answers PING only, 1 also READ, 2 everything. Broadcast
//!   instructions are executed and never answered, except PING, which every
//!   servo answers one after another in ascending ID order.
//! - A WRITE applies at once; the lock (55 on STS, 48 on SCS; closed at
//!   power-up) only decides whether EEPROM bytes survive
//!   [`SimServo::power_cycle`]. Read-only bytes (version, model, present
//!   values, reserved bytes) ignore writes; the write is still acknowledged.
//! - Writing the ID is answered from the old ID; the servo then answers to
//!   the new one only.
//! - REG WRITE holds its data (the register keeps its old value, the async
//!   flag at 64 reads 1) until ACTION.
//! - RESET restores every register to its factory value and saves it,
//!   **except the ID**, so that a reset servo stays addressable on a bus of
//!   many.
//! - Reads past the end of the table answer zeros for the missing bytes
//!   (the reply always has the requested length); writes past the end are
//!   ignored.
//! - A frame with a bad checksum is ignored; bytes before a header are
//!   skipped; a partial frame is dropped after the line has been idle for
//!   20 byte times.
//! - Torque enable without a goal holds the shaft where it is (the goal
//!   register follows the present position while torque is off); goal speed
//!   0 means the model's maximum speed; acceleration 0 means no limit; the
//!   homing offset (31) shifts both present and goal positions; writing 128
//!   to torque enable makes the present position 2048.
//!
//! # Example
//!
//! ```
//! use std::time::Duration;
//! use servobus_io::{Clock, ManualClock, Transport};
//! use servobus_protocol::{encode, parse_frame};
//! use servobus_sim::{addr, Faults, SimBus, SimServo};
//!
//! let clock = ManualClock::new();
//! let mut bus = SimBus::new(clock.clone(), 1_000_000)
//!     .with_servos((1..=3).map(|id| SimServo::sts3215(id).with_return_delay(Duration::ZERO)))
//!     .with_faults(Faults::seeded(7).drop(0.0));
//!
//! // Enable torque on every servo with one SYNC WRITE, then send a goal.
//! let mut frame = [0u8; 64];
//! let on = [1u8];
//! let n = encode::sync_write(&mut frame, addr::TORQUE_ENABLE, 1, (1..=3).map(|id| (id, &on[..])))
//!     .unwrap();
//! bus.write_all(&frame[..n]).unwrap();
//! let goal = 3000u16.to_le_bytes();
//! let n = encode::write(&mut frame, 2, addr::GOAL_POSITION, &goal).unwrap();
//! bus.write_all(&frame[..n]).unwrap();
//!
//! // One second of virtual time later the joint has arrived.
//! clock.advance(Duration::from_secs(1));
//! let n = encode::read(&mut frame, 2, addr::PRESENT_POSITION, 2).unwrap();
//! bus.discard_input().unwrap();
//! bus.write_all(&frame[..n]).unwrap();
//! let mut reply = [0u8; 16];
//! let got = bus.read(&mut reply, clock.now() + Duration::from_millis(1)).unwrap();
//! let (status, _) = parse_frame(&reply[..got]).unwrap();
//! let position = u16::from_le_bytes([status.params()[0], status.params()[1]]);
//! assert!((2999..=3001).contains(&position));
//! assert_eq!(bus.present_position(2), Some(i32::from(position)));
//! ```
#![warn(missing_docs)]

pub mod body;
mod bus;
mod dynamics;
mod engine;
mod faults;
pub mod floor;
pub mod model;
pub mod pty;
mod servo;
mod wall;

pub use body::{HandPath, Mount, Truth, TruthRow};
pub use bus::SimBus;
pub use engine::SimStats;
pub use faults::{FaultSpecError, Faults};
pub use floor::{pty_floor, Floor, FloorCycle};
pub use model::SimModel;
pub use pty::{PtyError, PtyServer};
pub use servo::{addr, SimServo};
pub use wall::WallBus;
