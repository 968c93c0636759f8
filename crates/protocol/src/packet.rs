//! A decoded packet as a borrowed view.

use crate::{checksum, Instruction, StatusFlags, FRAME_OVERHEAD};

/// One complete, checksum-verified frame, borrowing its bytes.
///
/// The same layout carries instructions (host to servo) and status replies
/// (servo to host); which one a frame is depends on who sent it, so the view
/// offers both readings of the fifth byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Packet<'a> {
    frame: &'a [u8],
}

impl<'a> Packet<'a> {
    /// Wraps a frame already known to be complete and valid.
    pub(crate) fn from_valid(frame: &'a [u8]) -> Self {
        Packet { frame }
    }

    /// The whole frame, header and checksum included.
    #[inline]
    pub fn bytes(&self) -> &'a [u8] {
        self.frame
    }
    /// The ID byte (254 for broadcast).
    #[inline]
    pub fn id(&self) -> u8 {
        self.frame[2]
    }
    /// Whether the packet is addressed to every servo.
    #[inline]
    pub fn is_broadcast(&self) -> bool {
        self.id() == crate::BROADCAST_ID
    }
    /// The length byte (parameters + 2).
    #[inline]
    pub fn length_byte(&self) -> u8 {
        self.frame[3]
    }
    /// The fifth byte: an instruction code or a status byte.
    #[inline]
    pub fn code(&self) -> u8 {
        self.frame[4]
    }
    /// The fifth byte read as an instruction, if it is a known one.
    #[inline]
    pub fn instruction(&self) -> Option<Instruction> {
        Instruction::from_code(self.code())
    }
    /// The fifth byte read as a status reply's error flags.
    #[inline]
    pub fn status(&self) -> StatusFlags {
        StatusFlags(self.code())
    }
    /// The parameter bytes.
    #[inline]
    pub fn params(&self) -> &'a [u8] {
        &self.frame[5..self.frame.len() - 1]
    }
    /// The checksum byte.
    #[inline]
    pub fn checksum(&self) -> u8 {
        self.frame[self.frame.len() - 1]
    }
}

/// Why [`parse_frame`] found no packet at the start of its input.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ParseError {
    /// The input does not start with `FF FF`.
    #[error("no packet header (FF FF) at the start")]
    NoHeader,
    /// The ID byte is 255, which no packet can have.
    #[error("invalid ID byte 0xFF")]
    InvalidId,
    /// The length byte is below 2.
    #[error("impossible length byte {0} (minimum 2)")]
    BadLength(u8),
    /// The input ends before the frame does.
    #[error("incomplete frame: {needed} bytes needed, {available} available")]
    Incomplete {
        /// The frame's full length (or 4 when even the length byte is missing).
        needed: usize,
        /// Bytes available.
        available: usize,
    },
    /// The checksum byte does not match the frame's contents.
    #[error("checksum mismatch: frame says 0x{found:02X}, contents give 0x{expected:02X}")]
    Checksum {
        /// The checksum the contents give.
        expected: u8,
        /// The checksum byte in the frame.
        found: u8,
    },
}

/// Parses the frame at the very start of `bytes`: the packet and the number
/// of bytes it spans. Bytes after it are ignored.
///
/// # Errors
/// A [`ParseError`] naming the first problem found.
pub fn parse_frame(bytes: &[u8]) -> Result<(Packet<'_>, usize), ParseError> {
    match check_frame(bytes) {
        Ok(len) => Ok((Packet::from_valid(&bytes[..len]), len)),
        Err(e) => Err(e),
    }
}

/// Validates the frame at the start of `bytes` and returns its length.
pub(crate) fn check_frame(bytes: &[u8]) -> Result<usize, ParseError> {
    if bytes.len() < 2 {
        if bytes.first().is_some_and(|&b| b != 0xFF) {
            return Err(ParseError::NoHeader);
        }
        return Err(ParseError::Incomplete {
            needed: 4,
            available: bytes.len(),
        });
    }
    if bytes[0] != 0xFF || bytes[1] != 0xFF {
        return Err(ParseError::NoHeader);
    }
    let Some(&id) = bytes.get(2) else {
        return Err(ParseError::Incomplete {
            needed: 4,
            available: bytes.len(),
        });
    };
    if id == 0xFF {
        return Err(ParseError::InvalidId);
    }
    let Some(&length) = bytes.get(3) else {
        return Err(ParseError::Incomplete {
            needed: 4,
            available: bytes.len(),
        });
    };
    if length < 2 {
        return Err(ParseError::BadLength(length));
    }
    let total = FRAME_OVERHEAD + usize::from(length) - 2;
    if bytes.len() < total {
        return Err(ParseError::Incomplete {
            needed: total,
            available: bytes.len(),
        });
    }
    let expected = checksum(&bytes[2..total - 1]);
    let found = bytes[total - 1];
    if expected != found {
        return Err(ParseError::Checksum { expected, found });
    }
    Ok(total)
}
