//! Allocation-free statistics for the control loop: a histogram of
//! microsecond values with percentiles, running RMS/max, and the one
//! definition of a 99th percentile over a window of samples ([`p99`]).

use std::time::Duration;

/// A histogram of durations in 1 us buckets up to a bound, with an exact
/// maximum. All memory is taken when it is built; recording never allocates.
#[derive(Debug, Clone)]
pub struct Histogram {
    buckets: Box<[u32]>,
    /// Samples at or above the last bucket.
    overflow: u64,
    count: u64,
    max: Duration,
    sum_nanos: u128,
}

impl Histogram {
    /// A histogram with 1 us resolution up to `bound` (values above it are
    /// counted and their maximum kept exactly, but percentiles falling among
    /// them report `bound`).
    pub fn new(bound: Duration) -> Self {
        let n = usize::try_from(bound.as_micros())
            .unwrap_or(usize::MAX)
            .clamp(1, 10_000_000);
        Histogram {
            buckets: vec![0; n].into_boxed_slice(),
            overflow: 0,
            count: 0,
            max: Duration::ZERO,
            sum_nanos: 0,
        }
    }

    /// Records one value.
    #[inline]
    pub fn record(&mut self, value: Duration) {
        let us = usize::try_from(value.as_micros()).unwrap_or(usize::MAX);
        match self.buckets.get_mut(us) {
            Some(b) => *b = b.saturating_add(1),
            None => self.overflow += 1,
        }
        self.count += 1;
        self.sum_nanos += value.as_nanos();
        if value > self.max {
            self.max = value;
        }
    }

    /// Number of values recorded.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// The largest value recorded (exact).
    pub fn max(&self) -> Duration {
        self.max
    }

    /// The mean of the values recorded.
    pub fn mean(&self) -> Duration {
        if self.count == 0 {
            return Duration::ZERO;
        }
        Duration::from_nanos(
            u64::try_from(self.sum_nanos / u128::from(self.count)).unwrap_or(u64::MAX),
        )
    }

    /// The `q` quantile (0.0..=1.0) to the microsecond: the smallest bucket
    /// value at or below which at least `q` of the samples lie.
    pub fn quantile(&self, q: f64) -> Duration {
        if self.count == 0 {
            return Duration::ZERO;
        }
        let rank = ((q.clamp(0.0, 1.0) * self.count as f64).ceil() as u64).max(1);
        let mut seen = 0u64;
        for (us, &n) in self.buckets.iter().enumerate() {
            seen += u64::from(n);
            if seen >= rank {
                // Never report more than the exact maximum.
                return Duration::from_micros(us as u64).min(self.max);
            }
        }
        self.max
    }

    /// Adds every value of `other` (same bound) into this histogram.
    pub fn merge(&mut self, other: &Histogram) {
        for (a, &b) in self.buckets.iter_mut().zip(other.buckets.iter()) {
            *a = a.saturating_add(b);
        }
        // Buckets `other` has beyond this one's bound count as overflow.
        let beyond: u64 = other
            .buckets
            .iter()
            .skip(self.buckets.len())
            .map(|&n| u64::from(n))
            .sum();
        self.overflow += other.overflow + beyond;
        self.count += other.count;
        self.sum_nanos += other.sum_nanos;
        self.max = self.max.max(other.max);
    }

    /// Forgets every value.
    pub fn clear(&mut self) {
        self.buckets.fill(0);
        self.overflow = 0;
        self.count = 0;
        self.max = Duration::ZERO;
        self.sum_nanos = 0;
    }
}

/// The 99th percentile of `values` by nearest rank (the value at rank
/// ceil(0.99 n), 1-based), ordered by `cmp`; `values` is reordered, nothing
/// is allocated. `None` when empty. Every p99 servobus shows over a window
/// of samples (the link's lateness, the monitor's reply times) is this one.
pub fn p99<T: Copy>(values: &mut [T], cmp: impl FnMut(&T, &T) -> std::cmp::Ordering) -> Option<T> {
    if values.is_empty() {
        return None;
    }
    let n = values.len();
    let rank = ((n * 99).div_ceil(100)).clamp(1, n);
    Some(*values.select_nth_unstable_by(rank - 1, cmp).1)
}

/// Running root-mean-square and maximum of absolute values.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RunningError {
    count: u64,
    sum_sq: f64,
    max_abs: f64,
}

impl RunningError {
    /// Adds one error value.
    #[inline]
    pub fn record(&mut self, error: f64) {
        if !error.is_finite() {
            return;
        }
        self.count += 1;
        self.sum_sq += error * error;
        self.max_abs = self.max_abs.max(error.abs());
    }
    /// Number of values recorded.
    pub fn count(&self) -> u64 {
        self.count
    }
    /// Root mean square (0 when empty).
    pub fn rms(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            (self.sum_sq / self.count as f64).sqrt()
        }
    }
    /// Largest absolute value.
    pub fn max_abs(&self) -> f64 {
        self.max_abs
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_99th_percentile_is_the_nearest_rank() {
        // 1..=200: rank ceil(198) = 198.
        let mut v: Vec<u32> = (1..=200).rev().collect();
        assert_eq!(p99(&mut v, u32::cmp), Some(198));
        // 1..=10: rank ceil(9.9) = 10, the largest.
        let mut v: Vec<f64> = (1..=10).map(f64::from).collect();
        assert_eq!(p99(&mut v, f64::total_cmp), Some(10.0));
        let mut none: [f64; 0] = [];
        assert_eq!(p99(&mut none, f64::total_cmp), None);
    }

    #[test]
    fn quantiles_of_a_known_distribution() {
        let mut h = Histogram::new(Duration::from_millis(1));
        for us in 1..=100u64 {
            h.record(Duration::from_micros(us));
        }
        assert_eq!(h.quantile(0.5), Duration::from_micros(50));
        assert_eq!(h.quantile(0.99), Duration::from_micros(99));
        assert_eq!(h.quantile(1.0), Duration::from_micros(100));
        h.record(Duration::from_millis(5));
        assert_eq!(h.max(), Duration::from_millis(5));
        assert_eq!(h.quantile(1.0), Duration::from_millis(5));
        assert_eq!(h.count(), 101);
    }

    #[test]
    fn rms_and_max() {
        let mut e = RunningError::default();
        for v in [3.0, -4.0, f64::NAN] {
            e.record(v);
        }
        assert_eq!(e.count(), 2);
        assert!((e.rms() - (12.5f64).sqrt()).abs() < 1e-12);
        assert_eq!(e.max_abs(), 4.0);
    }
}
