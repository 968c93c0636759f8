//! The serial link: baud rate, adapter latency, turnaround and margin, and
//! the reply deadlines derived from them.

use core::time::Duration;

use servobus_protocol::frame_len;

/// Bits on the wire per byte with 8N1 framing (start, 8 data, stop).
pub const BITS_PER_BYTE: u64 = 10;

/// A serial link to a bus of servos.
///
/// Every reply deadline is derived from these figures (never a fixed
/// timeout): request wire time + the servo's return delay + reply wire time
/// + adapter latency + turnaround + margin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Link {
    /// Baud rate in bits per second (any positive value, not only the table's).
    pub baud: u32,
    /// The adapter's latency per transaction (0 for an ideal link, about 1 ms
    /// for USB CDC/CH34x adapters, 16 ms for an FTDI at its default latency timer).
    pub latency: Duration,
    /// Gap between the end of a request and the start of the reply, on top of
    /// the servo's return delay.
    pub turnaround: Duration,
    /// Safety margin added to every deadline.
    pub margin: Duration,
}

impl Link {
    /// Default turnaround: the servo firmware's processing time before it
    /// starts its reply.
    pub const DEFAULT_TURNAROUND: Duration = Duration::from_micros(50);
    /// Default safety margin.
    pub const DEFAULT_MARGIN: Duration = Duration::from_micros(200);

    /// A link at `baud` with no adapter latency and the default turnaround and
    /// margin. A baud of 0 is treated as 1 so that nothing divides by zero.
    pub const fn new(baud: u32) -> Link {
        Link {
            baud: if baud == 0 { 1 } else { baud },
            latency: Duration::ZERO,
            turnaround: Self::DEFAULT_TURNAROUND,
            margin: Self::DEFAULT_MARGIN,
        }
    }

    /// The same link with the adapter latency set.
    pub const fn with_latency(mut self, latency: Duration) -> Link {
        self.latency = latency;
        self
    }

    /// The same link with the safety margin set.
    pub const fn with_margin(mut self, margin: Duration) -> Link {
        self.margin = margin;
        self
    }

    /// The same link with the turnaround set.
    pub const fn with_turnaround(mut self, turnaround: Duration) -> Link {
        self.turnaround = turnaround;
        self
    }

    /// Wire time of `bytes` bytes in whole nanoseconds, rounded up.
    pub const fn wire_nanos(&self, bytes: usize) -> u64 {
        let bits = (bytes as u64).saturating_mul(BITS_PER_BYTE);
        let baud = if self.baud == 0 { 1 } else { self.baud as u64 };
        // bits * 1e9 fits u64 for any frame count below ~1.8e9 bytes; beyond
        // that saturate rather than overflow.
        match bits.checked_mul(1_000_000_000) {
            Some(n) => n.div_ceil(baud),
            None => u64::MAX,
        }
    }

    /// Wire time of `bytes` bytes, rounded up to the nanosecond.
    pub const fn wire_time(&self, bytes: usize) -> Duration {
        Duration::from_nanos(self.wire_nanos(bytes))
    }

    /// Time from the start of sending a request of `request_bytes` until a
    /// reply of `reply_bytes` (sent after `return_delay`) must have arrived.
    pub fn reply_timeout(
        &self,
        request_bytes: usize,
        return_delay: Duration,
        reply_bytes: usize,
    ) -> Duration {
        self.wire_time(request_bytes)
            + return_delay
            + self.turnaround
            + self.wire_time(reply_bytes)
            + self.latency
            + self.margin
    }

    /// Deadline (from the start of sending) for the reply to a PING.
    pub fn ping_timeout(&self, return_delay: Duration) -> Duration {
        self.reply_timeout(frame_len(0), return_delay, frame_len(0))
    }

    /// Deadline for the reply to a READ of `len` bytes.
    pub fn read_timeout(&self, len: usize, return_delay: Duration) -> Duration {
        self.reply_timeout(frame_len(2), return_delay, frame_len(len))
    }

    /// Deadline for the status reply to a WRITE of `len` data bytes (only
    /// when the servo's status level asks for one).
    pub fn write_timeout(&self, len: usize, return_delay: Duration) -> Duration {
        self.reply_timeout(frame_len(1 + len), return_delay, frame_len(0))
    }

    /// Deadline for all `servos` replies of `len` bytes to a SYNC READ: the
    /// servos answer one after the other, each after its return delay.
    pub fn sync_read_timeout(&self, servos: usize, len: usize, return_delay: Duration) -> Duration {
        let n = servos as u32;
        self.wire_time(frame_len(2 + servos))
            + (return_delay + self.turnaround) * n
            + self.wire_time(servos * frame_len(len))
            + self.latency
            + self.margin
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wire_time_rounds_up_and_never_overflows() {
        let l = Link::new(1_000_000);
        assert_eq!(l.wire_time(1), Duration::from_micros(10));
        assert_eq!(l.wire_time(261), Duration::from_micros(2610));
        // 38400 baud: 10 bits = 260416.66.. ns, rounded up.
        assert_eq!(Link::new(38_400).wire_nanos(1), 260_417);
        // A non-standard rate.
        assert_eq!(Link::new(3).wire_nanos(1), 3_333_333_334);
        assert_eq!(Link::new(0).wire_nanos(1), 10_000_000_000);
        assert_eq!(Link::new(1).wire_nanos(usize::MAX), u64::MAX);
    }

    #[test]
    fn timeouts_at_1mbps_are_milliseconds_not_tens() {
        let l = Link::new(1_000_000).with_latency(Duration::from_millis(1));
        // READ of 2 bytes: 8 + 8 bytes = 160 us, + 50 us turnaround + 1 ms + 200 us.
        assert_eq!(
            l.read_timeout(2, Duration::ZERO),
            Duration::from_micros(1410)
        );
        // SYNC READ of 2 bytes from 6 servos: 14 + 48 bytes = 620 us, 6 x 50 us.
        assert_eq!(
            l.sync_read_timeout(6, 2, Duration::ZERO),
            Duration::from_micros(620 + 300 + 1000 + 200)
        );
    }
}
