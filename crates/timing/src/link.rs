//! The serial link: baud rate, adapter latency, turnaround and margin, and
//! the reply deadlines derived from them.

use core::time::Duration;

#[cfg(test)]
use servobus_protocol::MAX_FRAME_LEN;

/// Bits on the wire per byte with 8N1 framing (start, 8 data, stop).
pub const BITS_PER_BYTE: u64 = 10;

/// What a serial link adds to the wire time of every exchange, whatever
/// its baud rate: a [`Link`] without the rate. A bus's settings hold these,
/// and its transport the rate ([`LinkDelays::at`] joins them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LinkDelays {
    /// The adapter's latency per transaction ([`Link::latency`]).
    pub latency: Duration,
    /// Gap between a request and its reply beyond the return delay
    /// ([`Link::turnaround`]).
    pub turnaround: Duration,
    /// Safety margin added to every deadline ([`Link::margin`]).
    pub margin: Duration,
    /// Cost of each round trip beyond latency and wire ([`Link::overhead`]).
    pub overhead: Duration,
    /// Cost of each reply beyond its wire time ([`Link::reply_overhead`]).
    pub reply_overhead: Duration,
}

impl LinkDelays {
    /// No adapter latency, the default turnaround and margin, no
    /// overheads: [`Link::new`]'s.
    pub const DEFAULT: LinkDelays = Link::new(1).delays();

    /// The link these delays make at `baud` (0 is taken as 1, as by
    /// [`Link::new`]).
    pub const fn at(self, baud: u32) -> Link {
        Link {
            baud: if baud == 0 { 1 } else { baud },
            latency: self.latency,
            turnaround: self.turnaround,
            margin: self.margin,
            overhead: self.overhead,
            reply_overhead: self.reply_overhead,
        }
    }
}

impl Default for LinkDelays {
    fn default() -> Self {
        Self::DEFAULT
    }
}

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
    /// What each round trip (a request whose reply the host waits for)
    /// costs on this link beyond the adapter latency and the wire: the
    /// hand-offs between the host, the port and the far end. 0 on a link
    /// whose latency figure already covers them (a measured adapter);
    /// [`Link::PTY_EXCHANGE_OVERHEAD`] on the built-in simulator's
    /// pseudo-terminal.
    pub overhead: Duration,
    /// What each reply costs on this link beyond its wire time, return
    /// delay and turnaround (a hand-off per reply where the far end hands
    /// the replies over one by one); [`Link::PTY_REPLY_OVERHEAD`] on the
    /// built-in simulator's pseudo-terminal.
    pub reply_overhead: Duration,
}

impl Link {
    /// Default turnaround: the servo firmware's processing time before it
    /// starts its reply (the protocol crate's per-model figure).
    pub const DEFAULT_TURNAROUND: Duration = servobus_protocol::registers::REPLY_TURNAROUND;
    /// Default safety margin.
    pub const DEFAULT_MARGIN: Duration = Duration::from_micros(200);
    /// Latency of a USB serial adapter that is not an FTDI one: USB CDC and
    /// CH34x adapters deliver received bytes in 1 ms USB frames.
    pub const USB_LATENCY: Duration = Duration::from_millis(1);
    /// Latency allowed for a pseudo-terminal (the simulator behind
    /// `servobus sim`, or `play`'s simulated buses). The program at the other
    /// end is scheduled by the operating system, and on a loaded machine it
    /// now and then wakes milliseconds late; 3 ms is what simulated runs on a
    /// busy two-core machine have needed without spurious timeouts. It is an
    /// allowance for the simulator only: a real port uses
    /// [`Link::USB_LATENCY`] or its adapter's measured figure.
    pub const PTY_LATENCY: Duration = Duration::from_millis(3);
    /// What each round trip costs on the built-in simulator's
    /// pseudo-terminal beyond the wire and the servos' turnarounds: the
    /// kernel hands the request from the client to the simulator's thread
    /// and the reply back, a wake-up each way.
    ///
    /// How it was measured: `servobus bench --seconds 3` (release build,
    /// the simulator on a pty in the same process, a quiet 2-core machine)
    /// against the model without overheads: the SO-101 arm (one round
    /// trip, 6 replies) ran 79 us a cycle beyond the model, the SCS mini (4
    /// READs of one reply each) 251 us, the hexapod (one round trip, 18
    /// replies) 164 us. A SYNC READ's replies fit 7 us each; a round trip
    /// costs 37 us with a SYNC READ and 56 us with a READ (more host work
    /// per request). 60 us a round trip and 8 us a reply put every shipped
    /// robot within 2.5 % of what it achieved; on a busy machine bench runs
    /// up to about 6 % slower.
    pub const PTY_EXCHANGE_OVERHEAD: Duration = Duration::from_micros(60);
    /// What each reply costs on the built-in simulator's pseudo-terminal
    /// beyond its wire time and turnaround: the simulator hands each
    /// servo's reply over on its own (the turnaround between two replies
    /// is an idle line), one write and one wake-up of the client each.
    /// Measured with [`Link::PTY_EXCHANGE_OVERHEAD`].
    pub const PTY_REPLY_OVERHEAD: Duration = Duration::from_micros(8);

    /// A link at `baud` with no adapter latency and the default turnaround and
    /// margin. A baud of 0 is treated as 1 so that nothing divides by zero.
    pub const fn new(baud: u32) -> Link {
        Link {
            baud: if baud == 0 { 1 } else { baud },
            latency: Duration::ZERO,
            turnaround: Self::DEFAULT_TURNAROUND,
            margin: Self::DEFAULT_MARGIN,
            overhead: Duration::ZERO,
            reply_overhead: Duration::ZERO,
        }
    }

    /// The same link with the per-exchange costs set: `overhead` per round
    /// trip and `reply_overhead` per reply (see the fields).
    pub const fn with_overhead(mut self, overhead: Duration, reply_overhead: Duration) -> Link {
        self.overhead = overhead;
        self.reply_overhead = reply_overhead;
        self
    }

    /// The same link with the pseudo-terminal's per-exchange costs
    /// ([`Link::PTY_EXCHANGE_OVERHEAD`], [`Link::PTY_REPLY_OVERHEAD`]): the
    /// link of the built-in simulator.
    pub const fn on_pty(self) -> Link {
        self.with_overhead(Self::PTY_EXCHANGE_OVERHEAD, Self::PTY_REPLY_OVERHEAD)
    }

    /// What the link adds to `round_trips` round trips carrying `replies`
    /// replies in all, beyond wire time, return delays and turnarounds:
    /// the adapter latency and the overhead per round trip, the reply
    /// overhead per reply.
    pub fn exchange_cost(&self, round_trips: usize, replies: usize) -> Duration {
        let trips = u32::try_from(round_trips).unwrap_or(u32::MAX);
        let replies = u32::try_from(replies).unwrap_or(u32::MAX);
        self.latency
            .saturating_add(self.overhead)
            .saturating_mul(trips)
            .saturating_add(self.reply_overhead.saturating_mul(replies))
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

    /// What the link adds to the wire, without its baud rate.
    pub const fn delays(&self) -> LinkDelays {
        LinkDelays {
            latency: self.latency,
            turnaround: self.turnaround,
            margin: self.margin,
            overhead: self.overhead,
            reply_overhead: self.reply_overhead,
        }
    }

    /// Wire time of `bytes` bytes in whole nanoseconds, rounded up.
    ///
    /// Exact for every input: when `bits x 1e9` would overflow, the bit count
    /// is split into whole seconds and a remainder below one second; a result
    /// beyond `u64::MAX` ns (584 years) saturates.
    pub const fn wire_nanos(&self, bytes: usize) -> u64 {
        const NANOS_PER_SEC: u64 = 1_000_000_000;
        let bits = (bytes as u64).saturating_mul(BITS_PER_BYTE);
        let baud = if self.baud == 0 { 1 } else { self.baud as u64 };
        // Every real cycle (below 1.8e10 bits) takes this path: one division.
        if let Some(n) = bits.checked_mul(NANOS_PER_SEC) {
            return n.div_ceil(baud);
        }
        let whole_secs = bits / baud;
        // rem < baud <= u32::MAX, so rem * 1e9 < 4.3e18 fits a u64.
        let rem = bits % baud;
        let frac = (rem * NANOS_PER_SEC).div_ceil(baud);
        match whole_secs.checked_mul(NANOS_PER_SEC) {
            Some(n) => n.saturating_add(frac),
            None => u64::MAX,
        }
    }

    /// Wire time of `bytes` bytes, rounded up to the nanosecond.
    pub const fn wire_time(&self, bytes: usize) -> Duration {
        Duration::from_nanos(self.wire_nanos(bytes))
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

    /// Wire time of N bytes = ceil(N x 10 x 1e9 / baud) ns, worked out by
    /// hand for each entry: a baud rate, then `(bytes, ns)` at that rate.
    #[test]
    fn wire_time_table() {
        let frame = MAX_FRAME_LEN;
        let table: [(u32, &[(usize, u64)]); 12] = [
            // 1 Mbps: exactly 10 us a byte. The last entry is far more bytes
            // than any cycle (1e10 bits = 1e4 s): exact, no overflow
            // although bits x 1e9 would not fit a u64.
            (
                1_000_000,
                &[
                    (0, 0),
                    (1, 10_000),
                    (255, 2_550_000),
                    (frame, 2_590_000),
                    (1_000_000_000, 10_000_000_000_000),
                ],
            ),
            (500_000, &[(1, 20_000)]),
            (250_000, &[(1, 40_000)]),
            // 1e10 / 128000 = 78125 exactly: no rounding.
            (128_000, &[(1, 78_125)]),
            // 1e10 / 115200 = 86805.55.. -> 86806;
            // 2.55e12 / 115200 = 22135416.66.. -> 22135417.
            (115_200, &[(1, 86_806), (255, 22_135_417)]),
            // 1e10 / 76800 = 130208.33.. -> 130209 (rounds up, not to nearest).
            (76_800, &[(1, 130_209)]),
            // 1e10 / 57600 = 173611.11.. -> 173612;
            // 2.59e12 / 57600 = 44965277.7.. -> 44965278.
            (57_600, &[(1, 173_612), (frame, 44_965_278)]),
            // 1e10 / 38400 = 260416.66.. -> 260417; 2.55e12 / 38400 =
            // 66406250 exactly; 2.59e12 / 38400 = 67447916.66.. -> 67447917.
            (
                38_400,
                &[(1, 260_417), (255, 66_406_250), (frame, 67_447_917)],
            ),
            // Non-standard rates.
            (921_600, &[(1, 10_851), (frame, 2_810_330)]),
            (3, &[(1, 3_333_333_334)]),
            (1, &[(1, 10_000_000_000)]),
            // The fastest u32 baud: 1e10 / 4294967295 = 2.3.. -> 3.
            (u32::MAX, &[(1, 3), (frame, 604)]),
        ];
        for (baud, entries) in table {
            let l = Link::new(baud);
            for &(bytes, nanos) in entries {
                assert_eq!(l.wire_nanos(bytes), nanos, "{bytes} bytes at {baud} baud");
                assert_eq!(l.wire_time(bytes), Duration::from_nanos(nanos));
            }
        }
    }

    #[test]
    fn the_link_cost_of_exchanges_is_latency_and_overhead_per_trip_and_a_share_per_reply() {
        let l = Link::new(1_000_000)
            .with_latency(Duration::from_micros(1000))
            .with_overhead(Duration::from_micros(75), Duration::from_micros(10));
        // 4 READs of one reply each: 4 x (1000 + 75) + 4 x 10.
        assert_eq!(l.exchange_cost(4, 4), Duration::from_micros(4340));
        // One SYNC READ answered by 6: 1000 + 75 + 6 x 10.
        assert_eq!(l.exchange_cost(1, 6), Duration::from_micros(1135));
        assert_eq!(l.exchange_cost(0, 0), Duration::ZERO);
        // The simulator's pty: the named figures.
        let pty = Link::new(1_000_000).on_pty();
        assert_eq!(pty.exchange_cost(1, 6), Duration::from_micros(60 + 48));
        // A READ's deadline carries one round trip and one reply of it:
        // 8 + 8 bytes, 50 us turnaround, 68 us of the pty, 200 us margin.
        let read = crate::Transaction::Read { len: 2 };
        assert_eq!(
            pty.deadline(read, Duration::ZERO, crate::StatusLevel::All),
            Some(Duration::from_micros(160 + 50 + 68 + 200))
        );
    }

    #[test]
    fn wire_time_saturates_instead_of_overflowing() {
        // 1.9e9 bytes at 1 baud = 1.9e19 ns, over u64::MAX (1.84e19).
        assert_eq!(Link::new(1).wire_nanos(1_900_000_000), u64::MAX);
        assert_eq!(Link::new(1_000_000).wire_nanos(usize::MAX), u64::MAX);
        // usize::MAX bytes saturate to u64::MAX = (2^32 - 1)(2^32 + 1) bits;
        // at u32::MAX baud that is exactly 2^32 + 1 seconds.
        assert_eq!(
            Link::new(u32::MAX).wire_nanos(usize::MAX),
            4_294_967_297_000_000_000
        );
    }

    #[test]
    fn timeouts_at_1mbps_are_milliseconds_not_tens() {
        let l = Link::new(1_000_000).with_latency(Duration::from_millis(1));
        // READ of 2 bytes: 8 + 8 bytes = 160 us, + 50 us turnaround + 1 ms + 200 us.
        let all = crate::StatusLevel::All;
        let read = crate::Transaction::Read { len: 2 };
        assert_eq!(
            l.deadline(read, Duration::ZERO, all),
            Some(Duration::from_micros(1410))
        );
        // SYNC READ of 2 bytes from 6 servos: 14 + 48 bytes = 620 us, 6 x 50 us.
        let sync = crate::Transaction::SyncRead { servos: 6, len: 2 };
        assert_eq!(
            l.deadline(sync, Duration::ZERO, all),
            Some(Duration::from_micros(620 + 300 + 1000 + 200))
        );
    }
}
