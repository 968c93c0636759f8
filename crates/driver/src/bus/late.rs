//! Late replies: a reply that arrives after its deadline came from a servo
//! that answered, so it takes back the timeout its read was counted as.
//!
//! A Feetech servo answers on time or not at all: its firmware does not
//! hold a reply for milliseconds. When the bytes reach the host late, the
//! host was descheduled, or the adapter or (for a simulator on a
//! pseudo-terminal) the kernel's hand-off between the two ends was. The
//! read still lacked its reply when it needed it (the caller saw the servo
//! missing), but the servo is not silent: the counters say so, and a
//! servo that really is silent keeps every timeout it is counted.

use std::time::Duration;

use crate::{Bus, BusError, Clock, Transport};

impl<T: Transport> Bus<T> {
    /// Marks servo `id`'s reply as timed out: counted, and overdue until
    /// it comes.
    pub(crate) fn timed_out(&mut self, id: u8) {
        self.counters.timeouts += 1;
        self.servos[usize::from(id)].timeouts += 1;
        self.io.overdue(id);
    }

    /// Waits up to `within` for the replies of the servos whose last read
    /// timed out, and counts each that comes as a late reply instead of a
    /// timeout ([`BusCounters::late_replies`](crate::BusCounters::late_replies)).
    /// Returns at once when no reply is overdue, and as soon as none is.
    /// Waiting keeps the line quiet too: on a half-duplex bus the next
    /// request would collide with a late reply. Returns how many came.
    ///
    /// # Errors
    /// [`BusError::Transport`] when the port fails.
    pub fn await_late_replies(&mut self, within: Duration) -> Result<usize, BusError> {
        let deadline = self.io.transport.clock().now().saturating_add(within);
        self.io.take_late(deadline)?;
        Ok(self.count_late())
    }

    /// Counts the late replies the last look found; returns how many.
    pub(crate) fn count_late(&mut self) -> usize {
        let n = self.io.late_len;
        for &id in self.io.late() {
            for c in [&mut self.counters, &mut self.servos[usize::from(id)]] {
                c.timeouts = c.timeouts.saturating_sub(1);
                c.late_replies += 1;
            }
        }
        self.io.late_len = 0;
        n
    }
}
