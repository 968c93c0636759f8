//! [`BusError`]: why a bus transaction failed.

use std::time::Duration;

use servobus_protocol::{EncodeError, StatusFlags};

use crate::TransportError;

/// Why a transaction on a [`Bus`](crate::Bus) failed.
///
/// Errors that name a servo carry its ID; errors about a reply carry what was
/// expected and what came. Status flags reported by a servo are *not* an
/// error unless [`BusSettings::strict_status`](crate::BusSettings::strict_status)
/// is set: by default they are returned alongside the data.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BusError {
    /// No valid reply arrived before the deadline derived from the link.
    #[error("servo {id}: no reply within {} us", waited.as_micros())]
    Timeout {
        /// The servo asked.
        id: u8,
        /// How long the bus waited, from the start of sending the request.
        waited: Duration,
    },
    /// A reply arrived but its checksum was wrong (noise, or two servos with
    /// the same ID answering at once).
    #[error("servo {id}: corrupted reply (checksum error)")]
    Corrupt {
        /// The servo asked.
        id: u8,
    },
    /// A valid reply came from another servo than the one asked.
    #[error("servo {expected}: reply came from ID {actual}")]
    WrongId {
        /// The servo asked.
        expected: u8,
        /// The ID in the reply.
        actual: u8,
    },
    /// A reply from the right servo carried the wrong number of data bytes.
    #[error("servo {id}: reply carries {actual} data bytes, expected {expected}")]
    WrongLength {
        /// The servo asked.
        id: u8,
        /// Data bytes expected.
        expected: usize,
        /// Data bytes received.
        actual: usize,
    },
    /// The servo answered with error flags set, and the bus is configured to
    /// treat that as a failure.
    #[error("servo {id} reports {flags}")]
    Status {
        /// The servo.
        id: u8,
        /// Its status byte.
        flags: StatusFlags,
    },
    /// An EEPROM write read back different bytes than were written.
    #[error("servo {id}: register {address} reads back {actual:?} after writing {expected:?}")]
    Verify {
        /// The servo (its new ID when the ID itself was written).
        id: u8,
        /// The first address written.
        address: u8,
        /// The bytes written.
        expected: Vec<u8>,
        /// The bytes read back.
        actual: Vec<u8>,
    },
    /// The request could not be encoded (an ID out of range, too much data).
    #[error("cannot encode the request: {0}")]
    Encode(#[from] EncodeError),
    /// A value does not fit its register (e.g. an offset beyond +-2047).
    #[error(transparent)]
    Value(servobus_protocol::registers::ValueError),
    /// The arguments make no sense (e.g. a SYNC WRITE whose data is not a
    /// whole number of blocks, or a repeated ID in a SYNC READ).
    #[error("invalid request: {0}")]
    InvalidRequest(&'static str),
    /// The transport failed for another reason than a timeout: the port is
    /// gone or broken.
    #[error(transparent)]
    Transport(TransportError),
}

impl BusError {
    /// Whether trying the same transaction again may succeed (timeouts and
    /// corrupted or misrouted replies; not a dead port, not a bad request).
    pub fn is_retryable(&self) -> bool {
        matches!(
            self,
            BusError::Timeout { .. }
                | BusError::Corrupt { .. }
                | BusError::WrongId { .. }
                | BusError::WrongLength { .. }
        )
    }

    /// Whether the servo simply did not answer.
    pub fn is_timeout(&self) -> bool {
        matches!(self, BusError::Timeout { .. })
    }
}

impl From<TransportError> for BusError {
    fn from(e: TransportError) -> Self {
        BusError::Transport(e)
    }
}
