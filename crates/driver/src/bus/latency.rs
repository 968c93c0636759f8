//! The adapter's latency, measured with PINGs.

use std::time::Duration;

use servobus_protocol::frame_len;

use crate::{Bus, BusError, Clock, Transport};

impl<T: Transport, C: Clock> Bus<T, C> {
    /// Measures the adapter's latency with `samples` PINGs of servo `id`:
    /// each round trip minus what the link model already accounts for (wire
    /// time both ways, return delay, turnaround). Waits up to `ceiling` of
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
        if samples == 0 {
            return Err(BusError::InvalidRequest("no samples asked for"));
        }
        let saved = self.settings;
        self.settings.link.latency = ceiling;
        self.settings.retries = 0;
        let link = self.settings.link;
        let modelled = link.wire_time(frame_len(0) * 2) + saved.return_delay + link.turnaround;
        let mut m = LatencyMeasurement {
            samples: 0,
            min: Duration::MAX,
            mean: Duration::ZERO,
            max: Duration::ZERO,
        };
        let mut total = Duration::ZERO;
        let mut result = Ok(());
        for _ in 0..samples {
            if let Err(e) = self.ping(id) {
                result = Err(e);
                break;
            }
            let latency = self.last_rtt.saturating_sub(modelled);
            m.samples += 1;
            m.min = m.min.min(latency);
            m.max = m.max.max(latency);
            total += latency;
        }
        self.settings = saved;
        result?;
        m.mean = total / m.samples;
        Ok(m)
    }
}

/// The adapter latency measured by [`Bus::measure_latency`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LatencyMeasurement {
    /// PINGs measured.
    pub samples: u32,
    /// Smallest latency seen.
    pub min: Duration,
    /// Mean latency.
    pub mean: Duration,
    /// Largest latency seen: the value to configure.
    pub max: Duration,
}
