//! [`BusError`]: why a bus transaction failed.

use std::time::Duration;

use servobus_protocol::registers::Series;
use servobus_protocol::{EncodeError, StatusFlags};
use servobus_timing::StatusLevel;

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
    /// A value does not fit its register (e.g. an offset beyond +-2047), or
    /// bytes read do not decode as one.
    #[error(transparent)]
    Value(servobus_protocol::registers::ValueError),
    /// A servo is named twice in a request that takes each servo once (a
    /// SYNC READ or SYNC WRITE). Nothing is sent.
    #[error("servo {id} appears twice in one request")]
    DuplicateId {
        /// The repeated ID.
        id: u8,
    },
    /// An ID above the highest a servo can have (253) where a servo's ID is
    /// needed (a SYNC READ, a new ID). Nothing is sent.
    #[error("ID {id} is above 253, the highest a servo can have")]
    IdOutOfRange {
        /// The ID given.
        id: u8,
    },
    /// A write to a register the servos only let be read.
    #[error("register {address} is read-only")]
    ReadOnly {
        /// Its address.
        address: u8,
    },
    /// A register the bus's series does not have at that address with that
    /// layout (e.g. the signed STS position on SCS servos).
    #[error("register {address} is not one of the {series:?} servos' registers")]
    WrongSeries {
        /// The register's address.
        address: u8,
        /// The bus's series.
        series: Series,
    },
    /// A caller's buffer does not hold one result per servo of the request.
    #[error("the buffer holds {actual} results for a request of {expected} servos")]
    BufferLength {
        /// Results the request has (one per servo).
        expected: usize,
        /// Room in the buffer.
        actual: usize,
    },
    /// The servos' status level sends no reply to a request that needs one.
    #[error("the servos' status level ({level:?}) sends no reply to this request")]
    NotAnswered {
        /// The status level of the bus's settings.
        level: StatusLevel,
    },
    /// A servo's model-number register holds no known model, in either
    /// series' byte order.
    #[error("servo {id} reports model number {number}, which is not a known model")]
    UnknownModel {
        /// The servo.
        id: u8,
        /// Its model-number register as read (in the bus's byte order, or
        /// little-endian while the series is being found out).
        number: u16,
    },
    /// No servo answered a PING at the bus's baud rate.
    #[error("no servo answers at {baud} baud")]
    NoServo {
        /// The rate asked at.
        baud: u32,
    },
    /// The arguments make no sense in another way than the variants above
    /// name (e.g. a SYNC WRITE whose data is not a whole number of blocks,
    /// a SYNC READ of no servos).
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
