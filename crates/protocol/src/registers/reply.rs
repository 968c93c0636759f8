//! When a servo replies: which instructions its status level answers, and
//! the return delay (register 7) set from a duration.
//!
//! (The register-to-duration direction,
//! [`return_delay_from_register`](super::return_delay_from_register), is
//! beside the baud table.)

use core::time::Duration;

use super::{StatusLevel, RETURN_DELAY_UNIT};
use crate::Instruction;

impl StatusLevel {
    /// Whether a servo at this level replies to `inst` addressed to it.
    ///
    /// PING is always answered; READ and SYNC READ when reads are
    /// ([`StatusLevel::answers_reads`]); WRITE, REG WRITE, ACTION and RESET
    /// when writes are ([`StatusLevel::answers_writes`]); SYNC WRITE never.
    /// A broadcast other than PING and SYNC READ gets no reply at any level.
    ///
    /// ```
    /// use servobus_protocol::{registers::StatusLevel, Instruction};
    /// assert!(StatusLevel::PingOnly.answers(Instruction::Ping));
    /// assert!(!StatusLevel::PingOnly.answers(Instruction::Read));
    /// assert!(StatusLevel::PingAndRead.answers(Instruction::SyncRead));
    /// assert!(!StatusLevel::PingAndRead.answers(Instruction::Write));
    /// assert!(StatusLevel::All.answers(Instruction::Reset));
    /// assert!(!StatusLevel::All.answers(Instruction::SyncWrite));
    /// ```
    pub const fn answers(self, inst: Instruction) -> bool {
        match inst {
            Instruction::Ping => true,
            Instruction::Read | Instruction::SyncRead => self.answers_reads(),
            Instruction::Write
            | Instruction::RegWrite
            | Instruction::Action
            | Instruction::Reset => self.answers_writes(),
            Instruction::SyncWrite => false,
        }
    }
}

/// The return-delay register value (2 us units) for `delay`: rounded down,
/// at most 255 (510 us). The inverse of
/// [`return_delay_from_register`](super::return_delay_from_register) for
/// every register value.
///
/// ```
/// use core::time::Duration;
/// use servobus_protocol::registers::{return_delay_from_register, return_delay_register};
/// assert_eq!(return_delay_register(Duration::from_micros(500)), 250);
/// assert_eq!(return_delay_register(Duration::from_micros(7)), 3);
/// assert_eq!(return_delay_register(Duration::from_millis(2)), 255);
/// assert_eq!(return_delay_register(return_delay_from_register(17)), 17);
/// ```
pub const fn return_delay_register(delay: Duration) -> u8 {
    let units = delay.as_nanos() / RETURN_DELAY_UNIT.as_nanos();
    if units > 255 {
        255
    } else {
        units as u8
    }
}
