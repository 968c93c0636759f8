//! The broadcast PING: whether anyone at all answers at this baud rate,
//! asked once instead of once per ID.
//!
//! Every servo answers a PING sent to the broadcast ID (the one request to
//! that ID that is answered). With several servos on the bus their replies
//! follow one another or collide; either way bytes arrive. A baud rate at
//! which nothing arrives has no servo listening, and a scan can skip its
//! 254 IDs.

use std::time::Duration;

use servobus_protocol::{encode, BROADCAST_ID};
use servobus_timing::Transaction;

use crate::{Bus, BusError, Clock, Transport, TransportError};

/// The longest a broadcast PING listens for replies after the first byte:
/// 253 servos' replies at 38,400 baud take about 400 ms; a bus that is
/// still talking after this is not quiet whatever the scan waits.
const LISTEN_CAP: Duration = Duration::from_millis(500);

impl<T: Transport> Bus<T> {
    /// Sends a PING to the broadcast ID and tells whether any servo
    /// answered: bytes other than the request's own echo arrived within
    /// `at_least` or one PING's deadline (the bus's settings, as for a PING
    /// to one servo), whichever is longer. Garbled bytes count: two servos
    /// answering at once garble each other.
    ///
    /// When someone answered, it listens on until the line has been quiet
    /// for as long (at most half a second more), so that the request after
    /// it starts on a quiet line. An adapter that hands bytes over in bursts
    /// (a USB latency timer) needs `at_least` above its burst period.
    ///
    /// # Errors
    /// [`BusError::Transport`] when the port fails.
    pub fn anyone_answers(&mut self, at_least: Duration) -> Result<bool, BusError> {
        let s = &self.settings;
        // The deadline of a PING to one servo (the broadcast ID has none).
        let ping = self
            .link()
            .deadline(Transaction::Ping, s.return_delay, s.replies);
        let wait = ping.unwrap_or(Duration::ZERO).max(at_least);
        self.io.begin();
        self.io.tx_len = encode::ping(&mut self.io.tx, BROADCAST_ID)?;
        let start = self.send()?;
        let request = self.io.tx_len;
        let echo = self.io.echo;
        let mut heard = 0usize;
        // The bytes of the request's echo still to skip, in order.
        let mut echo_left = if echo { request } else { 0 };
        let mut buf = [0u8; 64];
        let mut deadline = start.saturating_add(wait);
        let cap = start.saturating_add(wait).saturating_add(LISTEN_CAP);
        loop {
            match crate::io::read_through_signals(&mut self.io.transport, &mut buf, deadline) {
                Ok(n) => {
                    for &b in &buf[..n] {
                        let at = request - echo_left;
                        if echo_left > 0 && self.io.tx.get(at) == Some(&b) {
                            echo_left -= 1;
                        } else {
                            echo_left = 0;
                            heard += 1;
                        }
                    }
                    if heard > 0 {
                        deadline = self
                            .io
                            .transport
                            .clock()
                            .now()
                            .saturating_add(wait)
                            .min(cap);
                    }
                }
                Err(TransportError::TimedOut) => break,
                Err(e) => return Err(e.into()),
            }
            if self.io.transport.clock().now() >= cap {
                break;
            }
        }
        Ok(heard > 0)
    }
}
