//! Encoders for every instruction (and for status packets, which the
//! simulator sends).
//!
//! Each encoder writes one complete frame at the start of a caller-owned
//! buffer and returns the frame's length. Nothing allocates, so the same
//! buffer can be reused every control cycle.
//!
//! The SYNC WRITE encoders, the one instruction whose speed matters every
//! control cycle, are in their own module and re-exported here.

mod sync;

pub use sync::{sync_write, sync_write_flat, sync_write_params};

use crate::{
    checksum, frame_len, is_servo_id, Command, Instruction, StatusFlags, BROADCAST_ID, MAX_PARAMS,
};

/// Why a frame could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum EncodeError {
    /// The caller's buffer cannot hold the frame.
    #[error("buffer too small: the frame needs {needed} bytes, the buffer has {available}")]
    BufferTooSmall {
        /// Bytes the frame needs.
        needed: usize,
        /// Bytes the buffer has.
        available: usize,
    },
    /// The ID is not a servo ID (0..=253), or not the broadcast ID where that is allowed.
    #[error("invalid servo ID {id} (valid: 0..=253{})", if *.broadcast_allowed { ", or 254 for broadcast" } else { "" })]
    InvalidId {
        /// The offending ID.
        id: u8,
        /// Whether the broadcast ID 254 would have been accepted.
        broadcast_allowed: bool,
    },
    /// The length byte would exceed 255.
    #[error("frame too long: its length byte would be {length}, {excess} over the maximum of 255")]
    FrameTooLong {
        /// The length byte the frame would need.
        length: usize,
        /// How far over 255 it is.
        excess: usize,
    },
    /// A SYNC WRITE data block does not have the announced length.
    #[error("data block for servo {id} has {actual} bytes, expected {expected}")]
    DataLength {
        /// The servo whose block is wrong.
        id: u8,
        /// The block length announced in the frame (L).
        expected: usize,
        /// The block length given.
        actual: usize,
    },
    /// A READ, SYNC READ or SYNC WRITE asked for zero bytes, or a WRITE carries no data.
    #[error("empty data: {what} needs at least one byte")]
    Empty {
        /// What was empty.
        what: &'static str,
    },
}

// The checks and `start` are `#[inline]`: the SYNC WRITE encoders in
// `sync.rs` call them every control cycle from another module, which without
// the hint may land in another codegen unit and pay a call each. `finish`,
// the checksum pass, is left to the compiler: a call costs little next to
// summing the whole frame.
#[inline]
fn check_id(id: u8, broadcast_allowed: bool) -> Result<(), EncodeError> {
    if is_servo_id(id) || (broadcast_allowed && id == BROADCAST_ID) {
        Ok(())
    } else {
        Err(EncodeError::InvalidId {
            id,
            broadcast_allowed,
        })
    }
}

#[inline]
fn check_params(params: usize) -> Result<(), EncodeError> {
    let length = params + 2;
    if params > MAX_PARAMS {
        Err(EncodeError::FrameTooLong {
            length,
            excess: length - crate::MAX_LENGTH_BYTE,
        })
    } else {
        Ok(())
    }
}

#[inline]
fn check_buf(buf: &[u8], params: usize) -> Result<usize, EncodeError> {
    let needed = frame_len(params);
    if buf.len() < needed {
        Err(EncodeError::BufferTooSmall {
            needed,
            available: buf.len(),
        })
    } else {
        Ok(needed)
    }
}

/// Writes header, ID, length and the fifth byte; parameters go at 5.. and the
/// checksum is added by [`finish`].
#[inline]
fn start(buf: &mut [u8], id: u8, params: usize, fifth: u8) {
    buf[0] = 0xFF;
    buf[1] = 0xFF;
    buf[2] = id;
    buf[3] = (params + 2) as u8;
    buf[4] = fifth;
}

fn finish(buf: &mut [u8], params: usize) -> usize {
    let end = 5 + params;
    buf[end] = checksum(&buf[2..end]);
    end + 1
}

/// A frame with an arbitrary fifth byte and parameters: the common path of
/// every encoder.
fn frame(buf: &mut [u8], id: u8, fifth: u8, params: &[&[u8]]) -> Result<usize, EncodeError> {
    let n: usize = params.iter().map(|p| p.len()).sum();
    check_params(n)?;
    check_buf(buf, n)?;
    start(buf, id, n, fifth);
    let mut at = 5;
    for p in params {
        buf[at..at + p.len()].copy_from_slice(p);
        at += p.len();
    }
    Ok(finish(buf, n))
}

/// PING `id` (broadcast allowed).
///
/// # Errors
/// [`EncodeError::InvalidId`] or [`EncodeError::BufferTooSmall`].
pub fn ping(buf: &mut [u8], id: u8) -> Result<usize, EncodeError> {
    check_id(id, true)?;
    frame(buf, id, Instruction::Ping.code(), &[])
}

/// READ `len` bytes from `address` of servo `id`.
///
/// # Errors
/// [`EncodeError::InvalidId`] (broadcast is refused: nobody would answer),
/// [`EncodeError::Empty`] for `len == 0`, or [`EncodeError::BufferTooSmall`].
pub fn read(buf: &mut [u8], id: u8, address: u8, len: u8) -> Result<usize, EncodeError> {
    check_id(id, false)?;
    if len == 0 {
        return Err(EncodeError::Empty { what: "READ" });
    }
    frame(buf, id, Instruction::Read.code(), &[&[address, len]])
}

/// WRITE `data` at `address` of servo `id` (broadcast allowed).
///
/// # Errors
/// [`EncodeError::InvalidId`], [`EncodeError::Empty`], [`EncodeError::FrameTooLong`]
/// or [`EncodeError::BufferTooSmall`].
pub fn write(buf: &mut [u8], id: u8, address: u8, data: &[u8]) -> Result<usize, EncodeError> {
    check_id(id, true)?;
    if data.is_empty() {
        return Err(EncodeError::Empty { what: "WRITE" });
    }
    frame(buf, id, Instruction::Write.code(), &[&[address], data])
}

/// REG WRITE `data` at `address` of servo `id`: held until ACTION.
///
/// # Errors
/// As [`write()`].
pub fn reg_write(buf: &mut [u8], id: u8, address: u8, data: &[u8]) -> Result<usize, EncodeError> {
    check_id(id, true)?;
    if data.is_empty() {
        return Err(EncodeError::Empty { what: "REG WRITE" });
    }
    frame(buf, id, Instruction::RegWrite.code(), &[&[address], data])
}

/// ACTION: execute held REG WRITE data (usually broadcast).
///
/// # Errors
/// [`EncodeError::InvalidId`] or [`EncodeError::BufferTooSmall`].
pub fn action(buf: &mut [u8], id: u8) -> Result<usize, EncodeError> {
    check_id(id, true)?;
    frame(buf, id, Instruction::Action.code(), &[])
}

/// RESET the memory table of servo `id` to factory values.
///
/// # Errors
/// [`EncodeError::InvalidId`] or [`EncodeError::BufferTooSmall`].
pub fn reset(buf: &mut [u8], id: u8) -> Result<usize, EncodeError> {
    check_id(id, true)?;
    frame(buf, id, Instruction::Reset.code(), &[])
}

/// SYNC READ `len` bytes from `address` of each servo in `ids`, which answer
/// in that order.
///
/// # Errors
/// [`EncodeError::InvalidId`] for any ID outside 0..=253, [`EncodeError::Empty`]
/// for no IDs or `len == 0`, [`EncodeError::FrameTooLong`] beyond 251 IDs, or
/// [`EncodeError::BufferTooSmall`].
pub fn sync_read(buf: &mut [u8], address: u8, len: u8, ids: &[u8]) -> Result<usize, EncodeError> {
    if len == 0 || ids.is_empty() {
        return Err(EncodeError::Empty { what: "SYNC READ" });
    }
    for &id in ids {
        check_id(id, false)?;
    }
    frame(
        buf,
        BROADCAST_ID,
        Instruction::SyncRead.code(),
        &[&[address, len], ids],
    )
}

/// A status packet from servo `id` with `flags` and `params` (what a servo
/// sends; used by the simulator and by tests).
///
/// # Errors
/// [`EncodeError::InvalidId`], [`EncodeError::FrameTooLong`] or
/// [`EncodeError::BufferTooSmall`].
pub fn status(
    buf: &mut [u8],
    id: u8,
    flags: StatusFlags,
    params: &[u8],
) -> Result<usize, EncodeError> {
    check_id(id, false)?;
    frame(buf, id, flags.bits(), &[params])
}

/// The frame of `command` addressed to `id`: the inverse of
/// [`Packet::command`](crate::Packet::command), for callers that hold a
/// request as a value (the driver's WRITE-like requests).
///
/// # Errors
/// As the encoder of the command's instruction.
pub fn command(buf: &mut [u8], id: u8, command: &Command<'_>) -> Result<usize, EncodeError> {
    match *command {
        Command::Ping => ping(buf, id),
        Command::Read { address, len } => read(buf, id, address, len),
        Command::Write { address, data } => write(buf, id, address, data),
        Command::RegWrite { address, data } => reg_write(buf, id, address, data),
        Command::Action => action(buf, id),
        Command::Reset => reset(buf, id),
        Command::SyncRead { address, len, ids } => sync_read(buf, address, len, ids),
        Command::SyncWrite(sw) => sync_write(buf, sw.address, sw.len, sw.blocks()),
    }
}
