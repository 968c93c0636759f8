//! Sending a request, and one single-servo transaction: send, wait for
//! the reply until the deadline, try again, count.

use std::time::Duration;

use servobus_protocol::registers::addr;
use servobus_protocol::{encode, parse_frame, Packet, StatusFlags, MAX_FRAME_LEN, MAX_PARAMS};
use servobus_timing::Transaction;

use crate::io::{PortEcho, Sink, Tally};
use crate::{Bus, BusError, Transport, TransportError};

impl<T: Transport> Bus<T> {
    /// Sends the request in the send buffer (after counting the late
    /// replies that arrived since the last look, [`Bus::await_late_replies`]),
    /// and returns the time it started on the wire: every request goes out
    /// here.
    pub(crate) fn send(&mut self) -> Result<Duration, TransportError> {
        let link = self.link();
        let start = self.io.send(&link);
        self.count_late();
        start
    }
}

/// What a single-servo transaction waits for.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Expect {
    /// The servo asked; a reply from `alt` is accepted too (an ID change).
    pub id: u8,
    pub alt: u8,
    /// Data bytes the reply carries.
    pub len: usize,
    /// Whether a reply comes at all.
    pub reply: bool,
    /// Deadline from the start of sending.
    pub timeout: Duration,
}

/// Collects the reply to a single-servo request.
struct Single<'a> {
    expect: Expect,
    out: &'a mut [u8; MAX_PARAMS],
    out_len: &'a mut usize,
    /// `(flags, arrival)` once the reply came.
    got: Option<(StatusFlags, Duration)>,
    /// The first wrong reply seen, if any.
    wrong: Option<BusError>,
    wrong_count: u64,
    corrupt: bool,
    /// Servos whose reply to an earlier request is overdue: a frame from
    /// one of them is that late reply, not a wrong one.
    owed: [bool; 256],
    /// Late replies seen: their IDs, in `late[..late_len]`.
    late: [u8; 256],
    late_len: usize,
}

impl<'a> Single<'a> {
    /// Waiting for `expect`, the reply's data into `out`; `owed`: the
    /// servos whose reply to an earlier request is overdue.
    fn new(
        expect: Expect,
        out: &'a mut [u8; MAX_PARAMS],
        out_len: &'a mut usize,
        owed: [bool; 256],
    ) -> Self {
        Single {
            expect,
            out,
            out_len,
            got: None,
            wrong: None,
            wrong_count: 0,
            corrupt: false,
            owed,
            late: [0; 256],
            late_len: 0,
        }
    }
}

impl Sink for Single<'_> {
    fn packet(&mut self, packet: &Packet<'_>, now: Duration) -> bool {
        let id = packet.id();
        let params = packet.params();
        let other = id != self.expect.id && id != self.expect.alt;
        if other && std::mem::take(&mut self.owed[usize::from(id)]) {
            // Another servo's reply to an earlier request, late.
            self.late[self.late_len] = id;
            self.late_len += 1;
            return false;
        }
        if !other
            && params.len() != self.expect.len
            && std::mem::take(&mut self.owed[usize::from(id)])
        {
            // This servo's late reply to an earlier request of another
            // length (a retried read's first try, say).
            self.late[self.late_len] = id;
            self.late_len += 1;
            return false;
        }
        let err = if other {
            BusError::WrongId {
                expected: self.expect.id,
                actual: id,
            }
        } else if params.len() != self.expect.len {
            BusError::WrongLength {
                id,
                expected: self.expect.len,
                actual: params.len(),
            }
        } else {
            self.out[..params.len()].copy_from_slice(params);
            *self.out_len = params.len();
            self.got = Some((packet.status(), now));
            return true;
        };
        self.wrong_count += 1;
        self.wrong.get_or_insert(err);
        false
    }

    fn checksum_error(&mut self, _id: u8) {
        // The ID byte of a corrupted frame cannot be trusted: any corruption
        // in the window of a single-servo request is taken as its reply
        // (two servos with one ID collide exactly like this).
        self.corrupt = true;
    }
}

impl<T: Transport> Bus<T> {
    /// Runs one single-servo transaction whose request is in `io.tx`, with
    /// bounded retries.
    pub(crate) fn transact(&mut self, expect: Expect) -> Result<Option<StatusFlags>, BusError> {
        let id = usize::from(expect.id);
        self.counters.transactions += 1;
        self.servos[id].transactions += 1;
        let mut last = None;
        for attempt in 0..=self.settings.retries {
            if attempt > 0 {
                self.counters.retries += 1;
                self.servos[id].retries += 1;
            }
            let start = self.send()?;
            if !expect.reply {
                return Ok(None);
            }
            // Overdue at the start: the reply taken may be the late one
            // to an earlier try, with this try's still to come.
            let owed_before = self.io.overdue_flags()[id];
            let owed = self.io.overdue_flags();
            let mut sink = Single::new(expect, &mut self.reply, &mut self.reply_len, owed);
            let tally = self.io.exchange(start + expect.timeout, &mut sink)?;
            let (got, wrong, wrong_count, corrupt) =
                (sink.got, sink.wrong, sink.wrong_count, sink.corrupt);
            for &late in &sink.late[..sink.late_len] {
                self.io.late_reply(late);
            }
            self.count_late();
            self.account(id, &tally, wrong_count);
            let got = match got {
                None if tally.ambiguous_copy && !corrupt && wrong.is_none() => {
                    self.resolve_copy(expect, tally.copy_at.unwrap_or(start))?
                }
                got => got,
            };
            if let Some((flags, at)) = got {
                if owed_before {
                    self.io.answered_in_doubt(expect.id);
                } else {
                    self.io.answered(expect.id);
                }
                let rtt = at.saturating_sub(start);
                self.last_rtt = rtt;
                self.counters.rtt.record(rtt);
                self.servos[id].rtt.record(rtt);
                if !flags.is_ok() {
                    self.counters.status_errors += 1;
                    self.servos[id].status_errors += 1;
                    if self.settings.strict_status {
                        return Err(BusError::Status {
                            id: expect.id,
                            flags,
                        });
                    }
                }
                return Ok(Some(flags));
            }
            // Bytes that arrived but made no valid frame are a garbled reply,
            // not silence.
            let err = if corrupt || tally.garbage_bytes > 0 {
                BusError::Corrupt { id: expect.id }
            } else if let Some(wrong) = wrong {
                wrong
            } else {
                self.timed_out(expect.id);
                BusError::Timeout {
                    id: expect.id,
                    waited: expect.timeout,
                }
            };
            last = Some(err);
        }
        self.counters.failures += 1;
        self.servos[id].failures += 1;
        Err(last.unwrap_or(BusError::Timeout {
            id: expect.id,
            waited: expect.timeout,
        }))
    }

    /// Decides whether the copy of the request skipped as its echo was the
    /// reply itself, on a port not yet known to echo (a servo with status
    /// 0x01 answers a PING with the PING's own bytes): asks servo
    /// `expect.id` for one byte, a request whose copy cannot be its reply.
    /// A copy of that shows the port echoes, and the skipped copy was the
    /// echo (the servo is silent); a clean reply with nothing before it
    /// shows the port does not, and the skipped copy was the reply, which
    /// is returned as arrived at `copy_at`. Anything else leaves the port
    /// unknown and the request unanswered. The request is left in the send
    /// buffer for a retry.
    fn resolve_copy(
        &mut self,
        expect: Expect,
        copy_at: Duration,
    ) -> Result<Option<(StatusFlags, Duration)>, BusError> {
        let mut saved = [0u8; MAX_FRAME_LEN];
        let n = self.io.tx_len;
        saved[..n].copy_from_slice(&self.io.tx[..n]);
        let probe = self.expect(expect.id, expect.id, 1, Transaction::Read { len: 1 });
        self.io.begin();
        self.io.tx_len = encode::read(&mut self.io.tx, expect.id, addr::ID, 1)?;
        let start = self.send()?;
        let mut byte = [0u8; MAX_PARAMS];
        let mut byte_len = 0;
        let mut sink = Single::new(probe, &mut byte, &mut byte_len, self.io.overdue_flags());
        let tally = self.io.exchange(start + probe.timeout, &mut sink)?;
        let (answered, wrong_count) = (sink.got.is_some(), sink.wrong_count);
        for &late in &sink.late[..sink.late_len] {
            self.io.late_reply(late);
        }
        self.count_late();
        self.account(usize::from(expect.id), &tally, wrong_count);
        if answered && tally.echoes == 0 && tally.garbage_bytes == 0 && tally.checksum_errors == 0 {
            self.io.port_echo = PortEcho::SILENT;
        }
        // The request back in the send buffer, for a retry.
        self.io.begin();
        self.io.tx[..n].copy_from_slice(&saved[..n]);
        self.io.tx_len = n;
        if self.io.port_echo.known != Some(false) {
            return Ok(None);
        }
        let Ok((packet, _)) = parse_frame(&saved[..n]) else {
            return Ok(None);
        };
        let params = packet.params();
        if packet.id() != expect.id || params.len() != expect.len {
            return Ok(None);
        }
        self.reply[..params.len()].copy_from_slice(params);
        self.reply_len = params.len();
        Ok(Some((packet.status(), copy_at)))
    }

    /// Adds what one wait saw to the bus counters and to servo `id`'s.
    pub(crate) fn account(&mut self, id: usize, tally: &Tally, wrong: u64) {
        for c in [&mut self.counters, &mut self.servos[id]] {
            c.echoes += tally.echoes;
            c.discarded_bytes += tally.discarded_bytes;
            c.checksum_errors += tally.checksum_errors;
            c.wrong_replies += wrong;
        }
    }
}
