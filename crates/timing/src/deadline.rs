//! Reply deadlines for every kind of transaction, taking the servo's status
//! level into account: a transaction that gets no reply has no deadline, and
//! the host must not wait for one.

use core::time::Duration;

use servobus_protocol::registers::StatusLevel;
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

impl Link {
    /// Deadline, measured from the start of sending the request, by which
    /// every reply to `tx` must have arrived, or `None` when the servo sends
    /// no reply at status level `level` (do not wait: the bus is free again
    /// once the request is out, after [`Link::request_time`]).
    ///
    /// The deadline is request wire time + for each reply (return delay +
    /// turnaround + reply wire time + the link's reply overhead) + adapter
    /// latency + the link's overhead + margin.
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
                .saturating_add(self.exchange_cost(1, replies))
                .saturating_add(self.margin),
        )
    }

    /// Time to send the request of `tx`: when a transaction that gets no
    /// reply has left the wire.
    pub fn request_time(&self, tx: Transaction) -> Duration {
        self.wire_time(tx.request_bytes())
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

    /// At 115200 baud a byte takes 86805.5.. ns; each wire time below is
    /// ceil(bytes x 1e10 / 115200) ns, worked out by hand.
    #[test]
    fn deadlines_at_115200_worked_by_hand() {
        let l = Link::new(115_200).with_latency(Duration::from_millis(1));
        let rd = US(500);
        let all = StatusLevel::All;
        // Return delay + turnaround = 550 us; latency + margin = 1200 us.
        let fixed = 550_000 + 1_200_000;
        let ns = Duration::from_nanos;
        // 6 + 6 bytes: 520834 ns each way.
        let ping = l.deadline(Transaction::Ping, rd, all);
        assert_eq!(ping, Some(ns(2 * 520_834 + fixed)));
        // 8 bytes out (694445 ns), 21 back (1822917 ns).
        let read = l.deadline(Transaction::Read { len: 15 }, rd, all);
        assert_eq!(read, Some(ns(694_445 + 1_822_917 + fixed)));
        // 11 bytes out (954862 ns), 6 back.
        let write = l.deadline(Transaction::Write { len: 4 }, rd, all);
        assert_eq!(write, Some(ns(954_862 + 520_834 + fixed)));
        // 26 bytes out (2256945 ns); 18 replies of 8 bytes (12.5 ms exactly),
        // each after its own return delay and turnaround.
        let sync = l.deadline(Transaction::SyncRead { servos: 18, len: 2 }, rd, all);
        assert_eq!(
            sync,
            Some(ns(2_256_945 + 18 * 550_000 + 12_500_000 + 1_200_000))
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
