//! servobus-timing: what every byte, reply and control cycle costs on a
//! Feetech serial bus, so that a robot's rate is proven before it moves.
//!
//! Pure integer arithmetic: no I/O, no clock, no allocation. Everything here
//! is derived from four facts about the bus ([`Link`]) and two about each
//! servo ([`Servo`]):
//!
//! - a byte is 10 bits on the wire (8N1), so it costs `10 / baud` seconds
//!   (10 us at 1 Mbps); wire times are whole nanoseconds, rounded up;
//! - a servo waits its return delay (register 7, 2 us units, factory 500 us)
//!   plus a short turnaround before it answers;
//! - a USB adapter adds its latency once per request the host waits on
//!   (about 1 ms for CDC/CH34x adapters, 16 ms for an FTDI at its default);
//! - STS/SMS servos answer SYNC READ; SCS servos must be read one by one.
//!
//! ```text
//!  one control cycle at 1 Mbps, 6 servos, goal position out, present position back
//!
//!  host  | SYNC WRITE 8+6x3 = 26 B | SYNC READ 8+6 = 14 B |
//!  servo |                         |                     | 1: 8 B | 2: 8 B | ... | 6: 8 B |
//!        0                        260                   400                              880 us
//!                                                          (each reply after its return delay)
//! ```
//!
//! The crate answers three questions:
//!
//! - **How long may I wait for a reply?** [`Link::deadline`] gives the
//!   deadline of every kind of [`Transaction`], or none when the servo's
//!   [`StatusLevel`] means no reply comes, instead of the fixed 16-100 ms of
//!   other libraries.
//! - **How do I send N goals?** [`pack_sync_write`] writes the fewest SYNC
//!   WRITE frames (each length byte <= 255) into a reused buffer.
//! - **Can this robot run at this rate?** [`plan`] costs the whole cycle
//!   ([`CycleCost`]), gives the maximum rate, and when the rate is too high
//!   either reads a round-robin subset of the servos each cycle
//!   ([`RoundRobin`]) or names the cheapest [`Change`] that would fit.
//!
//! ```
//! use core::time::Duration;
//! use servobus_timing::{pack_sync_write, plan, sync_write_bytes, Block, Link, Servo};
//!
//! // An SO-101 arm: 6 STS3215 at 1 Mbps behind a USB adapter with 1 ms latency.
//! let link = Link::new(1_000_000).with_latency(Duration::from_millis(1));
//! let servos: [Servo; 6] = core::array::from_fn(|i| Servo::sts(i as u8 + 1, Duration::ZERO));
//! let p = plan(&link, &servos, Some(Block::GOAL_POSITION), Some(Block::PRESENT_POSITION), 200.0)?;
//! assert_eq!(p.bytes_per_cycle(), 88);
//! assert!(p.is_feasible() && p.utilisation() < 0.5);
//!
//! // Each cycle: pack the goals into a buffer allocated once.
//! let ids: [u8; 6] = core::array::from_fn(|i| i as u8 + 1);
//! let goals = [0u8; 12]; // 6 x 2 bytes, little-endian ticks
//! let mut buf = [0u8; sync_write_bytes(6, 2)];
//! let packed = pack_sync_write(&mut buf, Block::GOAL_POSITION, &ids, &goals)?;
//! assert_eq!(link.wire_time(packed.len), Duration::from_micros(260));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]

mod block;
mod cost;
mod deadline;
mod error;
mod fix;
mod link;
mod pack;
mod plan;

pub use block::Block;
pub use cost::{floor_rate_hz, CycleCost, Servo, MAX_SYNC_READ_SERVOS};
pub use deadline::Transaction;
pub use fix::{Change, Fixes};
pub use link::{Link, LinkDelays, BITS_PER_BYTE};
pub use pack::{
    pack_sync_write, servos_per_frame, sync_write_bytes, sync_write_chunks, sync_write_frames,
    Chunk, PackError, Packed,
};
pub use plan::{plan, CycleError, Plan, RoundRobin, MAX_READ_LEN, MAX_SERVOS};
pub use servobus_protocol::registers::StatusLevel;
