//! Time, passed in: the [`Clock`] trait, the real monotonic clock and a
//! manual clock for virtual time.
//!
//! Every time in servobus is a [`Duration`] since the clock's epoch. Nothing
//! in the driver reads the wall clock directly; tests use [`ManualClock`] and
//! are deterministic.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A source of time and a way to wait for it.
pub trait Clock: Clone + Send + 'static {
    /// Time since this clock's epoch.
    fn now(&self) -> Duration;
    /// Returns once `now() >= deadline` (at once if it already is).
    fn sleep_until(&self, deadline: Duration);
}

/// The operating system's monotonic clock. Clones share the epoch.
#[derive(Debug, Clone, Copy)]
pub struct SystemClock {
    epoch: Instant,
}

impl SystemClock {
    /// A clock whose epoch is now.
    pub fn new() -> Self {
        SystemClock {
            epoch: Instant::now(),
        }
    }

    /// A clock with the given epoch, so that several clocks agree.
    pub fn with_epoch(epoch: Instant) -> Self {
        SystemClock { epoch }
    }

    /// The epoch as an [`Instant`].
    pub fn epoch(&self) -> Instant {
        self.epoch
    }
}

impl Default for SystemClock {
    fn default() -> Self {
        Self::new()
    }
}

impl Clock for SystemClock {
    fn now(&self) -> Duration {
        self.epoch.elapsed()
    }

    fn sleep_until(&self, deadline: Duration) {
        let now = self.now();
        if deadline > now {
            std::thread::sleep(deadline - now);
        }
    }
}

/// Virtual time that moves only when told to. Clones share the same time,
/// so a simulated bus and the code under test always agree on "now".
/// `sleep_until` jumps forward instantly.
#[derive(Debug, Clone, Default)]
pub struct ManualClock {
    nanos: Arc<AtomicU64>,
}

impl ManualClock {
    /// A clock at time zero.
    pub fn new() -> Self {
        Self::default()
    }

    /// Moves time forward by `by`.
    pub fn advance(&self, by: Duration) {
        self.nanos.fetch_add(saturating_nanos(by), Ordering::SeqCst);
    }

    /// Moves time forward to `t`; never moves it back.
    pub fn advance_to(&self, t: Duration) {
        self.nanos.fetch_max(saturating_nanos(t), Ordering::SeqCst);
    }
}

fn saturating_nanos(d: Duration) -> u64 {
    u64::try_from(d.as_nanos()).unwrap_or(u64::MAX)
}

impl Clock for ManualClock {
    fn now(&self) -> Duration {
        Duration::from_nanos(self.nanos.load(Ordering::SeqCst))
    }

    fn sleep_until(&self, deadline: Duration) {
        self.advance_to(deadline);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn manual_clock_clones_move_together_and_never_back() {
        let a = ManualClock::new();
        let b = a.clone();
        a.advance(Duration::from_micros(10));
        assert_eq!(b.now(), Duration::from_micros(10));
        b.sleep_until(Duration::from_micros(5));
        assert_eq!(a.now(), Duration::from_micros(10));
        b.sleep_until(Duration::from_millis(1));
        assert_eq!(a.now(), Duration::from_millis(1));
    }
}
