//! Counters kept per bus and per servo, and round-trip time statistics.
//!
//! Everything here is plain integers updated in place: counting never
//! allocates, so it is safe on the control loop's hot path.

use std::time::Duration;

/// Round-trip times: from the start of sending a request to the arrival of
/// the last byte of its reply (the last reply, for a SYNC READ).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RttStats {
    /// Number of round trips recorded.
    pub count: u64,
    /// Shortest, in nanoseconds (0 while `count == 0`).
    min_ns: u64,
    /// Longest, in nanoseconds.
    max_ns: u64,
    /// Sum of all, in nanoseconds.
    total_ns: u128,
    /// Sum of squares, in nanoseconds squared (for the standard deviation).
    total_sq_ns: u128,
}

impl RttStats {
    /// Records one round trip.
    pub fn record(&mut self, rtt: Duration) {
        let ns = u64::try_from(rtt.as_nanos()).unwrap_or(u64::MAX);
        if self.count == 0 || ns < self.min_ns {
            self.min_ns = ns;
        }
        self.max_ns = self.max_ns.max(ns);
        self.count += 1;
        self.total_ns += u128::from(ns);
        self.total_sq_ns += u128::from(ns) * u128::from(ns);
    }

    /// Shortest round trip, if any was recorded.
    pub fn min(&self) -> Option<Duration> {
        (self.count > 0).then(|| Duration::from_nanos(self.min_ns))
    }

    /// Longest round trip, if any was recorded.
    pub fn max(&self) -> Option<Duration> {
        (self.count > 0).then(|| Duration::from_nanos(self.max_ns))
    }

    /// Mean round trip, if any was recorded.
    pub fn mean(&self) -> Option<Duration> {
        (self.count > 0).then(|| nanos(self.total_ns / u128::from(self.count)))
    }

    /// Standard deviation of the round trips, if any was recorded.
    pub fn std_dev(&self) -> Option<Duration> {
        if self.count == 0 {
            return None;
        }
        let n = self.count as f64;
        let mean = self.total_ns as f64 / n;
        let var = (self.total_sq_ns as f64 / n - mean * mean).max(0.0);
        Some(Duration::from_nanos(var.sqrt() as u64))
    }

    /// Adds another set of statistics into this one.
    pub fn merge(&mut self, other: &RttStats) {
        if other.count == 0 {
            return;
        }
        if self.count == 0 || other.min_ns < self.min_ns {
            self.min_ns = other.min_ns;
        }
        self.max_ns = self.max_ns.max(other.max_ns);
        self.count += other.count;
        self.total_ns += other.total_ns;
        self.total_sq_ns += other.total_sq_ns;
    }
}

fn nanos(ns: u128) -> Duration {
    Duration::from_nanos(u64::try_from(ns).unwrap_or(u64::MAX))
}

/// What happened on a bus, or with one servo of it.
///
/// Bus-wide counters count requests; per-servo counters count what concerns
/// that servo (a SYNC READ of six servos is one bus transaction and one
/// transaction for each of the six).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BusCounters {
    /// Transactions started (retries not included).
    pub transactions: u64,
    /// Requests sent again after a failure (each re-ask counts one).
    pub retries: u64,
    /// Replies that did not arrive by their deadline (each attempt counts),
    /// less those that came later ([`late_replies`](Self::late_replies)).
    pub timeouts: u64,
    /// Replies that arrived after their deadline: the servo answered, and
    /// the host or the adapter delivered the bytes late (a servo's
    /// firmware answers on time or not at all). Counted when the bytes are
    /// seen, at the next request or by
    /// [`Bus::await_late_replies`](crate::Bus::await_late_replies); each
    /// takes back the timeout its read was counted as.
    pub late_replies: u64,
    /// Frames received with a bad checksum.
    pub checksum_errors: u64,
    /// Valid frames that were not the expected reply: another ID, the wrong
    /// length, or a second reply from a servo that had already answered.
    pub wrong_replies: u64,
    /// Echoes of our own requests skipped (half-duplex adapters).
    pub echoes: u64,
    /// Bytes received that belonged to no valid reply.
    pub discarded_bytes: u64,
    /// Replies whose status byte had error flags set.
    pub status_errors: u64,
    /// Transactions that failed for good (after every retry); for SYNC READ,
    /// servos still missing at the end.
    pub failures: u64,
    /// Round trips of successful replies.
    pub rtt: RttStats,
}

impl BusCounters {
    /// Adds another set of counters into this one.
    pub fn merge(&mut self, other: &BusCounters) {
        self.transactions += other.transactions;
        self.retries += other.retries;
        self.timeouts += other.timeouts;
        self.late_replies += other.late_replies;
        self.checksum_errors += other.checksum_errors;
        self.wrong_replies += other.wrong_replies;
        self.echoes += other.echoes;
        self.discarded_bytes += other.discarded_bytes;
        self.status_errors += other.status_errors;
        self.failures += other.failures;
        self.rtt.merge(&other.rtt);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rtt_stats_track_min_mean_max_and_spread() {
        let mut s = RttStats::default();
        assert_eq!(s.mean(), None);
        for us in [100, 300, 200] {
            s.record(Duration::from_micros(us));
        }
        assert_eq!(s.min(), Some(Duration::from_micros(100)));
        assert_eq!(s.max(), Some(Duration::from_micros(300)));
        assert_eq!(s.mean(), Some(Duration::from_micros(200)));
        // Population standard deviation of 100, 200, 300 us: 81.65 us.
        let sd = s.std_dev().unwrap_or_default().as_nanos();
        assert!((81_600..81_700).contains(&sd), "{sd}");
        let mut t = RttStats::default();
        t.record(Duration::from_micros(50));
        s.merge(&t);
        assert_eq!((s.count, s.min()), (4, Some(Duration::from_micros(50))));
    }
}
