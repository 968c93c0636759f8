//! A bus's timing figures: cycles run, deadlines skipped, how busy the bus
//! was and how regular the cycle starts were.

use std::time::Duration;

use crate::stats::Histogram;

/// What a cycle's timing was.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CycleTiming {
    pub index: u64,
    pub deadline: Duration,
    pub woke: Duration,
    /// Deadlines skipped before it, because an earlier cycle overran.
    pub skipped: u64,
}

/// See the module documentation.
#[derive(Debug, Clone)]
pub(crate) struct CycleTimes {
    pub cycles: u64,
    pub overruns: u64,
    pub busy_total: Duration,
    pub busy_max: Duration,
    /// Deviation of each start interval from the period(s) it spans.
    pub period_error: Histogram,
    /// When the first cycle was due: the achieved rate is counted from it, so
    /// that a first cycle woken late (a loaded machine) does not make the
    /// rate look higher than the plan.
    first_due: Option<Duration>,
    last: Option<CycleTiming>,
}

impl CycleTimes {
    pub fn new() -> Self {
        CycleTimes {
            cycles: 0,
            overruns: 0,
            busy_total: Duration::ZERO,
            busy_max: Duration::ZERO,
            period_error: Histogram::new(Duration::from_millis(100)),
            first_due: None,
            last: None,
        }
    }

    /// Records the start of a cycle of period `period`, and fills in the
    /// deadlines it skipped.
    pub fn begin(&mut self, timing: &mut CycleTiming, period: Duration) {
        timing.skipped = self
            .last
            .map_or(0, |l| timing.index.saturating_sub(l.index + 1));
        if let Some(last) = self.last {
            let n = u32::try_from(timing.index.saturating_sub(last.index)).unwrap_or(u32::MAX);
            let expected = period * n;
            let interval = timing.woke.saturating_sub(last.woke);
            self.period_error.record(interval.abs_diff(expected));
        }
        self.first_due.get_or_insert(timing.deadline);
        self.overruns += timing.skipped;
        self.cycles += 1;
        self.last = Some(*timing);
    }

    /// Records how long a cycle's bus work took.
    pub fn busy(&mut self, busy: Duration) {
        self.busy_total += busy;
        self.busy_max = self.busy_max.max(busy);
    }

    /// `(first woke, last woke, last deadline)` of the cycles run.
    pub fn span(&self) -> Option<(Duration, Duration, Duration)> {
        Some((self.first_due?, self.last?.woke, self.last?.deadline))
    }
}
