//! Deadlines that learn the link: how late replies really are, and the
//! adapter latency allowed for in every reply deadline.
//!
//! Each cycle's read reports its lateness: how long it took beyond what the
//! link model accounts for (wire time, return delays, turnarounds), that is
//! the adapter's latency as this bus sees it. With `x` the larger of the p99
//! over the last [`WINDOW`] reads and the largest of the last [`RECENT`],
//! the allowance in force is `x + x / 4 + HEADROOM`, bounded by [`CEILING`]. A read that times out sets the allowance to the ceiling at
//! once, so one late reply costs one miss, not three; the window then
//! brings it down to what the link really does.
//!
//! The ceiling keeps a silent servo from hiding behind a growing deadline:
//! every read of it times out within `CEILING` plus the wire time and margin
//! (under 4 ms for the SO-101 arm at 1 Mbps), so it is still declared
//! missing on the fault policy's count of cycles.

use std::time::Duration;

use servobus_driver::{Bus, BusSettings, Clock, Transport};
use servobus_timing::{Link, Transaction};

use super::feedback::Feedback;

/// Reads the allowance is learned over.
pub(crate) const WINDOW: usize = 256;

/// The largest adapter latency ever allowed for: the start-up probe's
/// ceiling ([`servobus_driver::PROBE_CEILING`], 3 ms).
pub(crate) const CEILING: Duration = servobus_driver::PROBE_CEILING;

/// The latest reads always count in full, whatever the percentile says:
/// a link that just slowed down shows in them before it shows in the p99.
pub(crate) const RECENT: usize = 16;

/// Added to the learned figure: room for scheduling noise.
pub(crate) const HEADROOM: Duration = Duration::from_micros(100);

/// PINGs and READs sent at start-up to measure the adapter (`latency_us:
/// auto`), before anything moves.
pub(crate) const PROBES: u32 = servobus_driver::PROBE_PINGS;

/// The learned latency of one bus.
#[derive(Debug, Clone)]
pub(crate) struct LinkLearner {
    /// The robot file gave a number: it wins, nothing is learned.
    fixed: bool,
    window: Vec<Duration>,
    /// Room to find the percentile in, so that a cycle allocates nothing.
    scratch: Vec<Duration>,
    next: usize,
    /// The window's 99th percentile, kept up to date by [`on_time`](Self::on_time).
    p99: Duration,
    /// The allowance in force.
    in_force: Duration,
    /// Every lateness seen, for the mean.
    total: Duration,
    count: u64,
}

impl LinkLearner {
    /// A learner starting at `latency`; `fixed` keeps it there.
    pub fn new(latency: Duration, fixed: bool) -> Self {
        LinkLearner {
            fixed,
            window: Vec::with_capacity(WINDOW),
            scratch: Vec::with_capacity(WINDOW),
            next: 0,
            p99: Duration::ZERO,
            in_force: latency.min(if fixed { Duration::MAX } else { CEILING }),
            total: Duration::ZERO,
            count: 0,
        }
    }

    /// The adapter latency to use in deadlines now.
    pub fn in_force(&self) -> Duration {
        self.in_force
    }

    /// Whether the allowance follows the link (`latency_us: auto`).
    pub fn learns(&self) -> bool {
        !self.fixed
    }

    /// A read whose replies all came, `lateness` beyond the link model.
    pub fn on_time(&mut self, lateness: Duration) {
        let evicted = if self.window.len() < WINDOW {
            self.window.push(lateness);
            None
        } else {
            Some(std::mem::replace(&mut self.window[self.next], lateness))
        };
        self.next = (self.next + 1) % WINDOW;
        self.total += lateness;
        self.count += 1;
        // A value at or below the p99 replacing one below it leaves the
        // p99 where it was: the steady state, which then costs no selection.
        let unchanged = matches!(evicted, Some(e) if e < self.p99 && lateness <= self.p99);
        if !unchanged {
            self.p99 = self.p99_now();
        }
        if !self.fixed {
            let x = self.p99.max(self.recent_max());
            self.in_force = (x + x / 4 + HEADROOM).min(CEILING);
        }
    }

    /// A read that timed out: allow the most at once.
    pub fn timed_out(&mut self) {
        if !self.fixed {
            self.in_force = CEILING;
        }
    }

    /// The 99th percentile of the window's lateness (0 before any read).
    pub fn p99(&self) -> Duration {
        self.p99
    }

    /// As [`p99`](Self::p99), in the learner's own scratch space.
    fn p99_now(&mut self) -> Duration {
        self.scratch.clear();
        self.scratch.extend_from_slice(&self.window);
        crate::stats::p99(&mut self.scratch, Duration::cmp).unwrap_or(Duration::ZERO)
    }

    /// The largest lateness of the last [`RECENT`] reads.
    fn recent_max(&self) -> Duration {
        let n = self.window.len();
        (1..=RECENT.min(n))
            .map(|back| self.window[(self.next + WINDOW - back) % WINDOW % n.max(1)])
            .max()
            .unwrap_or(Duration::ZERO)
    }

    /// The mean of every lateness seen.
    pub fn mean(&self) -> Duration {
        if self.count == 0 {
            Duration::ZERO
        } else {
            self.total / u32::try_from(self.count).unwrap_or(u32::MAX)
        }
    }
}

/// What the start-up measurement of the adapter did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Probe {
    /// Requests answered.
    pub requests: u32,
    /// How long the measurement took.
    pub took: Duration,
}

/// The position read's transaction on a bus of `settings` for `servos`
/// servos, and how many of it a cycle sends (one SYNC READ, or one READ per
/// servo).
fn read_of(settings: &BusSettings, servos: usize, len: usize) -> (Transaction, u32) {
    if settings.series.has_sync_read() {
        (Transaction::SyncRead { servos, len }, 1)
    } else {
        (
            Transaction::Read { len },
            u32::try_from(servos).unwrap_or(u32::MAX),
        )
    }
}

/// What the link model says reading `servos` positions takes, without the
/// adapter's latency and the margin: the time a perfect adapter would need,
/// on `link` (the bus's: [`Bus::link`]).
pub(crate) fn modelled(settings: &BusSettings, link: Link, servos: usize, len: usize) -> Duration {
    let (tx, n) = read_of(settings, servos, len);
    link.deadline(tx, settings.return_delay, settings.replies)
        .map_or(Duration::ZERO, |d| {
            d.saturating_sub(link.latency).saturating_sub(link.margin)
        })
        .saturating_mul(n)
}

/// The adapter allowance for one read of `servos` positions, whose fixed
/// cost is `model` (see [`modelled`]), when the cycle has `budget` left: the learned allowance `learned`, or, when the period
/// leaves more room than that, as much of the room as fits, up to
/// [`CEILING`].
///
/// Waiting longer for a reply costs nothing while the cycle would otherwise
/// sit idle until its next deadline, and a reply that a host stall made a
/// millisecond late is then a reading instead of a timeout and a re-ask (a
/// re-ask that can collide with the late reply on a half-duplex bus). A
/// silent servo is still declared missing after the same number of
/// cycles; at the fastest rate the budget allows, the room is nil and the
/// learned allowance alone sets the deadline.
pub(crate) fn allowance_within(
    settings: &BusSettings,
    servos: usize,
    len: usize,
    model: Duration,
    budget: Duration,
    learned: Duration,
) -> Duration {
    let (_, n) = read_of(settings, servos, len);
    let fixed = model + settings.link.margin.saturating_mul(n);
    let room = budget.saturating_sub(fixed) / n.max(1);
    learned.max(room.min(CEILING))
}

/// The reply deadline in force for reading `servos` positions (the sum of
/// the READs' on a bus without SYNC READ), on `link`.
pub(crate) fn deadline(settings: &BusSettings, link: Link, servos: usize, len: usize) -> Duration {
    let (tx, n) = read_of(settings, servos, len);
    link.deadline(tx, settings.return_delay, settings.replies)
        .unwrap_or(Duration::ZERO)
        .saturating_mul(n)
}

/// Measures the adapter before anything moves: [`PROBES`] PINGs, taking
/// the servos in turn, each waiting up to [`CEILING`] of latency
/// ([`Bus::probe_latency`], which `servobus budget --port` runs too). Every
/// answer teaches `learner` its lateness; a servo that does not answer is
/// left to the start-up read, which names it.
pub(crate) fn probe<T: Transport>(
    bus: &mut Bus<T>,
    clock: &T::Clock,
    learner: &mut LinkLearner,
    feedback: &Feedback,
) -> Probe {
    let began = clock.now();
    let measured = bus.probe_latency(feedback.ids(), PROBES, CEILING, |lateness| {
        learner.on_time(lateness);
    });
    Probe {
        requests: measured.map_or(0, |m| m.samples),
        took: clock.now().saturating_sub(began),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const US: Duration = Duration::from_micros(1);

    #[test]
    fn the_kept_p99_is_the_p99_of_the_last_window_of_reads() {
        let mut learner = LinkLearner::new(Duration::ZERO, false);
        let mut seen = Vec::new();
        // A fixed pseudo-random sequence with long quiet runs and bursts,
        // so that both the kept and the recomputed paths are taken.
        let mut x: u64 = 12345;
        for i in 0..3000u64 {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let burst = (i / 400) % 2 == 1;
            let us = (x >> 33) % if burst { 3000 } else { 200 };
            let lateness = Duration::from_micros(us);
            learner.on_time(lateness);
            seen.push(lateness);
            // By hand, nearest rank: sort the last 256 and take rank
            // ceil(0.99 x 256) = 254, index 253 (fewer reads: ceil(0.99 n)).
            let mut last: Vec<_> = seen[seen.len().saturating_sub(WINDOW)..].to_vec();
            last.sort();
            let rank = (last.len() * 99).div_ceil(100);
            let want = last[rank - 1];
            assert_eq!(learner.p99(), want, "after {} reads", i + 1);
        }
    }

    #[test]
    fn a_roomy_cycle_waits_longer_than_learned_and_a_tight_one_does_not() {
        let settings = BusSettings::new(servobus_protocol::registers::Series::Sts);
        // Six positions by SYNC READ at 1 Mbps, return delay 0: a request of
        // 14 bytes and 6 replies of 8, 620 us on the wire, plus 6
        // turnarounds of 50 us: 920 us that no adapter can shorten.
        let model = modelled(&settings, settings.link.at(1_000_000), 6, 2);
        assert_eq!(model, 920 * US);
        let fixed = model + settings.link.margin;
        let learned = 400 * US;
        // A 200 Hz cycle with 3.5 ms left: the room is past the ceiling.
        assert_eq!(
            allowance_within(&settings, 6, 2, model, 3500 * US + fixed, learned),
            CEILING
        );
        // 1 ms of room: all of it.
        assert_eq!(
            allowance_within(&settings, 6, 2, model, 1000 * US + fixed, learned),
            1000 * US
        );
        // Less room than learned (the fastest rate): the learned allowance.
        assert_eq!(
            allowance_within(&settings, 6, 2, model, 100 * US + fixed, learned),
            learned
        );
        assert_eq!(
            allowance_within(&settings, 6, 2, model, Duration::ZERO, learned),
            learned
        );
    }

    #[test]
    fn a_jump_from_0_to_1_ms_costs_one_miss_and_ends_with_a_deadline_that_fits() {
        let mut l = LinkLearner::new(Duration::ZERO, false);
        for _ in 0..500 {
            l.on_time(Duration::ZERO);
        }
        assert_eq!(l.in_force(), HEADROOM);
        // The link slows down: the first read at the old allowance times out.
        l.timed_out();
        assert_eq!(l.in_force(), CEILING);
        // Every following read fits the ceiling; the allowance settles just
        // above the new latency.
        for _ in 0..WINDOW {
            l.on_time(1000 * US);
            assert!(l.in_force() > 1000 * US);
        }
        assert_eq!(l.in_force(), (1250 + 100) * US);
        assert_eq!(l.p99(), 1000 * US);
        // And back down once the link is fast again, past the recent reads
        // and the p99's share of the window.
        for _ in 0..WINDOW {
            l.on_time(Duration::ZERO);
        }
        assert_eq!(l.in_force(), HEADROOM);
    }

    #[test]
    fn the_allowance_never_exceeds_the_ceiling() {
        let mut l = LinkLearner::new(Duration::from_secs(1), false);
        assert_eq!(l.in_force(), CEILING);
        for _ in 0..10 {
            l.on_time(Duration::from_millis(50));
            l.timed_out();
        }
        assert_eq!(l.in_force(), CEILING);
    }

    #[test]
    fn a_number_in_the_robot_file_wins() {
        let mut l = LinkLearner::new(5000 * US, true);
        l.on_time(10 * US);
        l.timed_out();
        assert_eq!(l.in_force(), 5000 * US);
        assert_eq!(l.mean(), 10 * US);
    }

    #[test]
    fn the_p99_ignores_one_outlier_in_a_hundred() {
        let mut l = LinkLearner::new(Duration::ZERO, false);
        for i in 0..200u32 {
            l.on_time(if i % 100 == 0 { 1500 * US } else { 100 * US });
        }
        // Past the recent reads too.
        for _ in 0..RECENT {
            l.on_time(100 * US);
        }
        assert_eq!(l.p99(), 100 * US);
        assert_eq!(l.in_force(), (125 + 100) * US);
    }
}
