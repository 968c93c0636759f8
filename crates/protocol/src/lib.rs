//! Feetech SCS/STS/SMS serial-bus servo protocol: packets, checksums, a
//! streaming decoder and register maps.
//!
//! Everything servobus says to a servo, and everything it hears back, goes
//! through this crate; the driver, the simulator and `servobus decode` share
//! it so that they cannot disagree about a byte. It does no I/O, reads no
//! clock and never allocates while encoding or decoding: encoders write into
//! a caller-owned buffer that is reused every control cycle, and decoded
//! packets are views borrowing the bytes they came from. That keeps the
//! control loop's hot path allocation-free and lets the crate run `no_std`.
//!
//! # Packets
//!
//! ```text
//!  0    1    2    3     4            5 .. 5+N-1      5+N
//! +----+----+----+-----+------------+---------------+----------+
//! | FF | FF | ID | LEN | INST / ERR | P1 .. PN      | CHECKSUM |
//! +----+----+----+-----+------------+---------------+----------+
//!                LEN = N + 2        CHECKSUM = !(ID + LEN + INST + sum P) & 0xFF
//!
//!  SYNC WRITE (0x83), ID FE:  P = ADDR L  ID1 D1..DL  ID2 D1..DL ...
//!  SYNC READ  (0x82), ID FE:  P = ADDR L  ID1 ID2 ...   (STS/SMS only)
//! ```
//!
//! A host sends instruction packets (the fifth byte is the [`Instruction`]);
//! a servo answers with a status packet (the fifth byte is its
//! [`StatusFlags`]). ID 254 ([`BROADCAST_ID`]) addresses every servo; only
//! PING is answered when broadcast.
//!
//! # Map of the crate
//!
//! - [`encode`]: one function per instruction (and status replies, for the
//!   simulator), writing into `&mut [u8]` and returning the frame length.
//! - [`parse_frame`] and [`Packet`]: one frame at the start of a slice;
//!   [`Packet::command`] reads an instruction's parameters as a [`Command`].
//! - [`Decoder`]: the streaming decoder for bytes that arrive in arbitrary
//!   chunks, with garbage, corrupted frames and a half-duplex adapter's echo;
//!   every byte is accounted for in an [`Event`].
//! - [`registers`]: the STS/SMS and SCS control tables, models, and
//!   sign-magnitude value conversion in both byte orders.
//!
//! # Example
//!
//! ```
//! use servobus_protocol::registers::{ByteOrder, STS};
//! use servobus_protocol::{encode, Decoder, Event, Instruction};
//!
//! let mut buf = [0u8; 16];
//! // Read two bytes of present position (address 0x38) from servo 1.
//! let n = encode::read(&mut buf, 1, 0x38, 2).unwrap();
//! assert_eq!(&buf[..n], &[0xFF, 0xFF, 0x01, 0x04, 0x02, 0x38, 0x02, 0xBE]);
//!
//! let (packet, used) = servobus_protocol::parse_frame(&buf[..n]).unwrap();
//! assert_eq!(used, n);
//! assert_eq!(packet.instruction(), Some(Instruction::Read));
//!
//! // The reply arrives in two pieces, after the adapter echoed the request.
//! let mut dec = Decoder::new();
//! dec.expect_echo(&buf[..n]);
//! let wire = [&buf[..n], &[0xFF, 0xFF, 0x01, 0x04], &[0x00, 0x18, 0x05, 0xDD]];
//! let mut position = None;
//! for mut chunk in wire {
//!     while let Some(event) = dec.decode(&mut chunk) {
//!         if let Event::Packet { packet, .. } = event {
//!             assert!(packet.status().is_ok());
//!             let reg = STS.get("present_position").unwrap();
//!             position = Some(reg.decode(packet.params(), ByteOrder::Little).unwrap());
//!         }
//!     }
//! }
//! assert_eq!(position, Some(1304));
//! assert_eq!(dec.stats().echoes, 1);
//! ```
#![no_std]
#![warn(missing_docs)]

#[cfg(feature = "alloc")]
extern crate alloc;
#[cfg(feature = "std")]
extern crate std;

#[macro_use]
mod names;

mod checksum;
mod command;
pub mod decoder;
pub mod encode;
mod instruction;
mod packet;
pub mod registers;

pub use checksum::checksum;
pub use command::{Command, CommandError, SyncWrite};
pub use decoder::{Decoder, DecoderStats, DiscardReason, Event};
pub use encode::EncodeError;
pub use instruction::{Instruction, StatusFlags};
pub use packet::{parse_frame, Packet, ParseError};

/// The two bytes that open every packet.
pub const HEADER: [u8; 2] = [0xFF, 0xFF];
/// The broadcast ID: every servo executes the instruction; only PING is answered.
pub const BROADCAST_ID: u8 = 0xFE;
/// The highest ID a single servo can have.
pub const MAX_ID: u8 = 253;
/// Bytes of a frame besides its parameters: header (2), ID, length, instruction, checksum.
pub const FRAME_OVERHEAD: usize = 6;
/// The largest value of the length byte.
pub const MAX_LENGTH_BYTE: usize = 255;
/// The largest number of parameters one frame can carry (`MAX_LENGTH_BYTE - 2`).
pub const MAX_PARAMS: usize = MAX_LENGTH_BYTE - 2;
/// The longest possible frame in bytes.
pub const MAX_FRAME_LEN: usize = FRAME_OVERHEAD + MAX_PARAMS;

/// Length in bytes of a frame that carries `params` parameter bytes.
#[inline]
pub const fn frame_len(params: usize) -> usize {
    FRAME_OVERHEAD + params
}

/// Whether `id` may address a single servo (0..=253).
#[inline]
pub const fn is_servo_id(id: u8) -> bool {
    id <= MAX_ID
}
