//! The adapter's latency, measured with PINGs.

use std::time::Duration;

use servobus_timing::Transaction;

use crate::{Bus, BusError, Transport};

/// PINGs of the start-up measurement of an adapter ([`Bus::probe_latency`]
/// as a run with `latency_us: auto` and `servobus budget --port` send it).
pub const PROBE_PINGS: u32 = 32;

/// The most latency a PING of that measurement waits for: 3 ms, beyond
/// every USB adapter with a 1 ms latency timer, and the allowance a
/// pseudo-terminal on a busy machine has needed
/// ([`Link::PTY_LATENCY`](servobus_timing::Link::PTY_LATENCY)).
pub const PROBE_CEILING: Duration = servobus_timing::Link::PTY_LATENCY;

impl<T: Transport> Bus<T> {
    /// Measures the adapter's latency with `samples` PINGs of servo `id`:
    /// each round trip minus what the link model already accounts for (wire
    /// time both ways, return delay, turnaround, the link's overheads). Waits up to `ceiling` of
    /// latency per PING. Does not change the settings: pass the result to
    /// [`Bus::set_latency`] (the maximum is the safe choice).
    ///
    /// # Errors
    /// [`BusError::InvalidRequest`] for zero samples; the first failed PING's
    /// error.
    pub fn measure_latency(
        &mut self,
        id: u8,
        samples: u32,
        ceiling: Duration,
    ) -> Result<LatencyMeasurement, BusError> {
        let mut first_error = None;
        let m = self.pings(&[id], samples, ceiling, |_| {}, &mut first_error)?;
        match first_error {
            Some(e) => Err(e),
            None => Ok(m),
        }
    }

    /// Measures the adapter's latency with `samples` PINGs taking the
    /// servos `ids` in turn, as [`Bus::measure_latency`] does for one
    /// servo, and hands each answered PING's latency to `each` (the
    /// runtime's learner takes them; `servobus budget --port` the mean). A
    /// servo that does not answer is passed over: finding it is for the
    /// reads that follow.
    ///
    /// # Errors
    /// [`BusError::InvalidRequest`] for zero samples or no IDs; the first
    /// failed PING's error when none was answered, and at once when the
    /// transport fails.
    pub fn probe_latency(
        &mut self,
        ids: &[u8],
        samples: u32,
        ceiling: Duration,
        each: impl FnMut(Duration),
    ) -> Result<LatencyMeasurement, BusError> {
        let mut first_error = None;
        let m = self.pings(ids, samples, ceiling, each, &mut first_error)?;
        match first_error {
            Some(e) if m.samples == 0 => Err(e),
            _ => Ok(m),
        }
    }

    /// The PINGs of [`Bus::probe_latency`]: a transport failure ends them
    /// with its error; the first other failure is kept in `first_error`.
    fn pings(
        &mut self,
        ids: &[u8],
        samples: u32,
        ceiling: Duration,
        mut each: impl FnMut(Duration),
        first_error: &mut Option<BusError>,
    ) -> Result<LatencyMeasurement, BusError> {
        if samples == 0 || ids.is_empty() {
            return Err(BusError::InvalidRequest("no samples asked for"));
        }
        let saved = self.settings;
        self.settings.link.latency = ceiling;
        self.settings.retries = 0;
        // What the link model accounts for: the PING's deadline without the
        // latency and the margin.
        let link = self.link();
        let modelled = link
            .deadline(Transaction::Ping, saved.return_delay, saved.replies)
            .map_or(Duration::ZERO, |d| {
                d.saturating_sub(link.latency).saturating_sub(link.margin)
            });
        let mut m = LatencyMeasurement {
            samples: 0,
            min: Duration::MAX,
            mean: Duration::ZERO,
            median: Duration::ZERO,
            max: Duration::ZERO,
        };
        let mut total = Duration::ZERO;
        // Every answered PING's latency, for the median (not the hot path).
        let mut seen = Vec::with_capacity(samples.min(1024) as usize);
        let mut result = Ok(());
        for &id in ids.iter().cycle().take(samples as usize) {
            match self.ping(id) {
                Ok(_) => {}
                Err(e @ BusError::Transport(_)) => {
                    result = Err(e);
                    break;
                }
                Err(e) => {
                    if first_error.is_none() {
                        *first_error = Some(e);
                    }
                    if ids.len() == 1 {
                        // One servo, and it failed: the measurement is over.
                        break;
                    }
                    continue;
                }
            }
            let latency = self.last_rtt.saturating_sub(modelled);
            each(latency);
            seen.push(latency);
            m.samples += 1;
            m.min = m.min.min(latency);
            m.max = m.max.max(latency);
            total += latency;
        }
        self.settings = saved;
        result?;
        if m.samples > 0 {
            m.mean = total / m.samples;
            seen.sort_unstable();
            m.median = seen[seen.len() / 2];
        } else {
            m.min = Duration::ZERO;
        }
        Ok(m)
    }
}

/// The adapter latency measured by [`Bus::measure_latency`] or
/// [`Bus::probe_latency`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LatencyMeasurement {
    /// PINGs answered and measured.
    pub samples: u32,
    /// Smallest latency seen.
    pub min: Duration,
    /// Mean latency.
    pub mean: Duration,
    /// Median latency (the upper one of an even count): the typical
    /// exchange, which one stall of a loaded host does not move.
    pub median: Duration,
    /// Largest latency seen: the value to configure.
    pub max: Duration,
}
