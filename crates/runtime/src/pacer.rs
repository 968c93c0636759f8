//! Fixed-rate pacing from absolute deadlines.
//!
//! Cycle `k` is due at `start + k * period`: deadlines are computed, never
//! accumulated, so there is no drift. The wait sleeps until shortly before
//! the deadline and spins for the last stretch, because operating-system
//! sleeps wake late by tens of microseconds. A cycle that ends after the next
//! deadline is an overrun: the pacer skips to the next deadline still ahead
//! and counts the skipped ones; it never bursts to catch up.

use std::time::Duration;

use servobus_driver::Clock;

/// What one call to [`Pacer::wait`] found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tick {
    /// Index of the cycle that is now due (`start + index * period`).
    pub index: u64,
    /// Its deadline on the clock's time base.
    pub deadline: Duration,
    /// When the wait returned.
    pub woke: Duration,
    /// Deadlines skipped because the previous cycle overran them.
    pub skipped: u64,
}

impl Tick {
    /// How late the wake-up was relative to the deadline.
    pub fn lateness(&self) -> Duration {
        self.woke.saturating_sub(self.deadline)
    }
}

/// Paces a loop at a fixed period on any [`Clock`].
#[derive(Debug, Clone)]
pub struct Pacer<C: Clock> {
    clock: C,
    start: Duration,
    period: Duration,
    spin: Duration,
    next: u64,
    overruns: u64,
}

/// Spins without seeing the clock move are taken as a virtual clock, which
/// only moves when slept on.
const STILL_CLOCK_SPINS: u32 = 1_000;

impl<C: Clock> Pacer<C> {
    /// A pacer whose cycle 0 is due at `start`. A zero period is raised to 1 ns.
    pub fn new(clock: C, start: Duration, period: Duration) -> Self {
        Pacer {
            clock,
            start,
            period: period.max(Duration::from_nanos(1)),
            spin: Duration::ZERO,
            next: 0,
            overruns: 0,
        }
    }

    /// Spin (instead of sleeping) for the last `spin` before each deadline.
    pub fn with_spin(mut self, spin: Duration) -> Self {
        self.spin = spin;
        self
    }

    /// The period.
    pub fn period(&self) -> Duration {
        self.period
    }

    /// The deadline of cycle `index`.
    pub fn deadline(&self, index: u64) -> Duration {
        self.start + mul(self.period, index)
    }

    /// The index of the next cycle [`wait`](Self::wait) can return (it may
    /// return a later one, skipping deadlines an overrun missed).
    pub fn next_index(&self) -> u64 {
        self.next
    }

    /// Deadlines skipped so far because cycles overran.
    pub fn overruns(&self) -> u64 {
        self.overruns
    }

    /// The clock.
    pub fn clock(&self) -> &C {
        &self.clock
    }

    /// Waits for the next cycle's deadline and returns it. If that deadline
    /// has already passed by a whole period or more, the missed deadlines
    /// are skipped (and counted) and the wait is for the first one ahead;
    /// a deadline passed by less than a period is returned at once.
    pub fn wait(&mut self) -> Tick {
        let now = self.clock.now();
        let mut index = self.next;
        let mut skipped = 0;
        let due = self.deadline(index);
        if now >= due + self.period {
            // `now` lies beyond the next deadline too: skip to the first
            // deadline that is still ahead.
            let elapsed = now - self.start;
            let ahead = (elapsed.as_nanos() / self.period.as_nanos()) as u64 + 1;
            skipped = ahead - index;
            index = ahead;
            self.overruns += skipped;
        }
        let deadline = self.deadline(index);
        self.sleep_until(deadline);
        self.next = index + 1;
        Tick {
            index,
            deadline,
            woke: self.clock.now(),
            skipped,
        }
    }

    fn sleep_until(&self, deadline: Duration) {
        let now = self.clock.now();
        if now >= deadline {
            return;
        }
        if self.spin.is_zero() {
            self.clock.sleep_until(deadline);
            return;
        }
        if deadline - now > self.spin {
            self.clock.sleep_until(deadline - self.spin);
        }
        let mut last = self.clock.now();
        let mut still = 0u32;
        loop {
            let now = self.clock.now();
            if now >= deadline {
                return;
            }
            if now == last {
                still += 1;
                if still >= STILL_CLOCK_SPINS {
                    self.clock.sleep_until(deadline);
                    return;
                }
            } else {
                still = 0;
                last = now;
            }
            std::hint::spin_loop();
        }
    }
}

fn mul(d: Duration, k: u64) -> Duration {
    let nanos = d.as_nanos().saturating_mul(u128::from(k));
    Duration::from_nanos(u64::try_from(nanos).unwrap_or(u64::MAX))
}

#[cfg(test)]
mod tests {
    use super::*;
    use servobus_driver::ManualClock;

    #[test]
    fn deadlines_are_absolute_and_overruns_skip() {
        let clock = ManualClock::new();
        let mut p = Pacer::new(clock.clone(), Duration::ZERO, Duration::from_millis(2))
            .with_spin(Duration::from_micros(100));
        let t = p.wait();
        assert_eq!((t.index, t.deadline, t.skipped), (0, Duration::ZERO, 0));
        clock.advance(Duration::from_micros(700));
        let t = p.wait();
        assert_eq!((t.index, t.woke), (1, Duration::from_millis(2)));
        // Work takes 5.1 ms: deadlines 2 (4 ms) and 3 (6 ms) are missed.
        clock.advance(Duration::from_micros(5_100));
        let t = p.wait();
        assert_eq!((t.index, t.skipped), (4, 2));
        assert_eq!(t.woke, Duration::from_millis(8));
        assert_eq!(p.overruns(), 2);
        // Late by less than a period: returned at once, nothing skipped.
        clock.advance(Duration::from_micros(2_500));
        let t = p.wait();
        assert_eq!((t.index, t.skipped), (5, 0));
        assert_eq!(t.lateness(), Duration::from_micros(500));
        // 10,000 cycles later there is no drift.
        for _ in 0..10_000 {
            clock.advance(Duration::from_micros(300));
            p.wait();
        }
        assert_eq!(clock.now(), Duration::from_millis(2 * 10_005));
    }
}
