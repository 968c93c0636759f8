//! Reply deadlines for every kind of transaction, taking the servo's status
//! level into account: a transaction that gets no reply has no deadline, and
//! the host must not wait for one.

use core::time::Duration;

use servobus_protocol::{encode::sync_write_params, frame_len};

use crate::Link;

/// One transaction with a single servo (or, for SYNC READ and SYNC WRITE,
/// with several), described by what decides its wire time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Transaction {
    /// PING: an empty request, an empty reply.
    Ping,
    /// READ of `len` bytes: a 2-parameter request, a reply of `len` bytes.
    Read {
        /// Bytes read.
        len: usize,
    },
    /// WRITE of `len` data bytes to one servo; answered only at status level
    /// "all".
    Write {
        /// Data bytes written (the address byte not counted).
        len: usize,
    },
    /// REG WRITE of `len` data bytes to one servo; answered as WRITE is.
    RegWrite {
        /// Data bytes written.
        len: usize,
    },
    /// ACTION to one servo; answered as WRITE is. A broadcast ACTION is
    /// never answered.
    Action,
    /// RESET of one servo; answered as WRITE is.
    Reset,
    /// SYNC READ of `len` bytes from `servos` servos, which answer one after
    /// the other in the order of the request.
    SyncRead {
        /// Servos listed in the request.
        servos: usize,
        /// Bytes read from each.
        len: usize,
    },
    /// SYNC WRITE of `len`-byte blocks to `servos` servos in one frame:
    /// broadcast, never answered.
    SyncWrite {
        /// Servos in the frame.
        servos: usize,
        /// Block length.
        len: usize,
    },
}

impl Transaction {
    /// Bytes of the request frame.
    pub const fn request_bytes(&self) -> usize {
        match *self {
            Transaction::Ping | Transaction::Action | Transaction::Reset => frame_len(0),
            Transaction::Read { .. } => frame_len(2),
            Transaction::Write { len } | Transaction::RegWrite { len } => frame_len(1 + len),
            Transaction::SyncRead { servos, .. } => frame_len(2 + servos),
            Transaction::SyncWrite { servos, len } => frame_len(sync_write_params(servos, len)),
        }
    }

    /// Bytes of each status reply (whether or not one is sent).
    pub const fn reply_bytes(&self) -> usize {
        match *self {
            Transaction::Read { len } | Transaction::SyncRead { len, .. } => frame_len(len),
            _ => frame_len(0),
        }
    }

    /// How many status replies come back at status level `level`.
    pub const fn replies(&self, level: StatusLevel) -> usize {
        match *self {
            Transaction::Ping => 1,
            Transaction::Read { .. } => level.answers_reads() as usize,
            Transaction::SyncRead { servos, .. } => {
                if level.answers_reads() {
                    servos
                } else {
                    0
                }
            }
            Transaction::Write { .. }
            | Transaction::RegWrite { .. }
            | Transaction::Action
            | Transaction::Reset => level.answers_writes() as usize,
            Transaction::SyncWrite { .. } => 0,
        }
    }
}

/// Which instructions a servo answers: its status level (register 8).
///
/// STS/SMS servos: 0 answers PING and READ only, 1 answers everything.
/// SCS servos (SCS0009): 0 answers PING only, 1 PING and READ, 2 everything.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum StatusLevel {
    /// Only PING is answered.
    PingOnly,
    /// PING, READ and SYNC READ are answered; writes are not.
    PingAndRead,
    /// Every instruction addressed to one servo is answered (the factory
    /// setting).
    #[default]
    All,
}

impl StatusLevel {
    /// The level of an STS/SMS servo whose register 8 holds `value`.
    pub const fn from_sts(value: u8) -> StatusLevel {
        if value == 0 {
            StatusLevel::PingAndRead
        } else {
            StatusLevel::All
        }
    }

    /// The level of an SCS servo whose register 8 holds `value`.
    pub const fn from_scs(value: u8) -> StatusLevel {
        match value {
            0 => StatusLevel::PingOnly,
            1 => StatusLevel::PingAndRead,
            _ => StatusLevel::All,
        }
    }

    /// Whether READ and SYNC READ are answered.
    pub const fn answers_reads(self) -> bool {
        !matches!(self, StatusLevel::PingOnly)
    }

    /// Whether WRITE, REG WRITE, ACTION and RESET are answered.
    pub const fn answers_writes(self) -> bool {
        matches!(self, StatusLevel::All)
    }
}

impl Link {
    /// Deadline, measured from the start of sending the request, by which
    /// every reply to `tx` must have arrived, or `None` when the servo sends
    /// no reply at status level `level` (do not wait: the bus is free again
    /// once the request is out, after [`Link::request_time`]).
    ///
    /// The deadline is request wire time + for each reply (return delay +
    /// turnaround + reply wire time) + adapter latency + margin.
    pub fn deadline(
        &self,
        tx: Transaction,
        return_delay: Duration,
        level: StatusLevel,
    ) -> Option<Duration> {
        let replies = tx.replies(level);
        if replies == 0 {
            return None;
        }
        let per_reply = return_delay.saturating_add(self.turnaround);
        let waits = per_reply
            .checked_mul(u32::try_from(replies).unwrap_or(u32::MAX))
            .unwrap_or(Duration::MAX);
        Some(
            self.wire_time(tx.request_bytes())
                .saturating_add(waits)
                .saturating_add(self.wire_time(replies.saturating_mul(tx.reply_bytes())))
                .saturating_add(self.latency)
                .saturating_add(self.margin),
        )
    }

    /// Time to send the request of `tx`: when a transaction that gets no
    /// reply has left the wire.
    pub fn request_time(&self, tx: Transaction) -> Duration {
        self.wire_time(tx.request_bytes())
    }

    /// Deadline for the status reply to a WRITE of `len` data bytes at status
    /// level `level`, or `None` when the servo does not reply to writes.
    pub fn write_deadline(
        &self,
        len: usize,
        return_delay: Duration,
        level: StatusLevel,
    ) -> Option<Duration> {
        self.deadline(Transaction::Write { len }, return_delay, level)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const US: fn(u64) -> Duration = Duration::from_micros;

    /// 1 Mbps, no latency, no turnaround, no margin: deadlines are pure wire
    /// time plus the return delay, easy to check by hand.
    fn bare() -> Link {
        Link::new(1_000_000)
            .with_turnaround(Duration::ZERO)
            .with_margin(Duration::ZERO)
    }

    #[test]
    fn every_kind_at_status_level_all() {
        let l = bare();
        let rd = US(20);
        let all = StatusLevel::All;
        let table: [(Transaction, Option<u64>); 8] = [
            // 6 + 6 bytes + 20 us.
            (Transaction::Ping, Some(140)),
            // 8 + (6 + 2) bytes + 20 us.
            (Transaction::Read { len: 2 }, Some(180)),
            // 6 + 1 + 2 = 9 request bytes, 6 reply bytes.
            (Transaction::Write { len: 2 }, Some(170)),
            (Transaction::RegWrite { len: 7 }, Some(140 + 60 + 20)),
            (Transaction::Action, Some(140)),
            (Transaction::Reset, Some(140)),
            // 14 + 6 x 8 bytes + 6 x 20 us.
            (Transaction::SyncRead { servos: 6, len: 2 }, Some(620 + 120)),
            (Transaction::SyncWrite { servos: 6, len: 2 }, None),
        ];
        for (tx, expected) in table {
            assert_eq!(l.deadline(tx, rd, all), expected.map(US), "{tx:?}");
        }
    }

    #[test]
    fn status_level_decides_whether_writes_are_answered() {
        let l = bare();
        let w = Transaction::Write { len: 2 };
        assert_eq!(
            l.deadline(w, Duration::ZERO, StatusLevel::All),
            Some(US(150))
        );
        assert_eq!(
            l.deadline(w, Duration::ZERO, StatusLevel::PingAndRead),
            None
        );
        assert_eq!(
            l.write_deadline(2, Duration::ZERO, StatusLevel::from_sts(0)),
            None
        );
        assert_eq!(l.request_time(w), US(90));
        let r = Transaction::Read { len: 2 };
        assert_eq!(
            l.deadline(r, Duration::ZERO, StatusLevel::from_sts(0)),
            Some(US(160))
        );
        assert_eq!(
            l.deadline(r, Duration::ZERO, StatusLevel::from_scs(0)),
            None
        );
        assert_eq!(
            l.deadline(Transaction::Ping, Duration::ZERO, StatusLevel::PingOnly),
            Some(US(120))
        );
        assert_eq!(StatusLevel::from_scs(1), StatusLevel::PingAndRead);
        assert_eq!(StatusLevel::from_scs(2), StatusLevel::All);
        assert_eq!(StatusLevel::from_sts(1), StatusLevel::All);
    }

    #[test]
    fn deadline_agrees_with_the_named_timeouts() {
        let l = Link::new(115_200).with_latency(Duration::from_millis(1));
        let rd = US(500);
        let all = StatusLevel::All;
        assert_eq!(
            l.deadline(Transaction::Ping, rd, all),
            Some(l.ping_timeout(rd))
        );
        assert_eq!(
            l.deadline(Transaction::Read { len: 15 }, rd, all),
            Some(l.read_timeout(15, rd))
        );
        assert_eq!(
            l.deadline(Transaction::Write { len: 4 }, rd, all),
            Some(l.write_timeout(4, rd))
        );
        assert_eq!(
            l.deadline(Transaction::SyncRead { servos: 18, len: 2 }, rd, all),
            Some(l.sync_read_timeout(18, 2, rd))
        );
    }

    #[test]
    fn latency_and_margin_are_added_once() {
        let l = bare()
            .with_latency(Duration::from_millis(16))
            .with_margin(US(200))
            .with_turnaround(US(50));
        // 14 + 48 bytes = 620 us, 6 x 50 us turnaround, 16 ms, 200 us.
        assert_eq!(
            l.deadline(
                Transaction::SyncRead { servos: 6, len: 2 },
                Duration::ZERO,
                StatusLevel::All
            ),
            Some(US(620 + 300 + 16_000 + 200))
        );
    }
}
