//! SYNC READ rounds: the request, the replies matched to servos by ID, and
//! the re-asks of the servos still missing.

use std::time::Duration;

use servobus_protocol::{encode, Packet, BROADCAST_ID, MAX_PARAMS};
use servobus_timing::Transaction;

use super::results::{MissingReason, Slot, SyncRead, SyncStore};
use crate::io::Sink;
use crate::stats::BusCounters;
use crate::{Bus, BusError, Clock, Transport};

/// Added to every reply timeout by [`Bus::sync_read_patiently`].
pub const PATIENCE: Duration = Duration::from_millis(100);
/// Rounds [`Bus::sync_read_patiently`] makes before a servo counts as
/// missing.
pub const PATIENT_TRIES: u8 = 3;
/// Collects the replies of one SYNC READ round.
struct Round<'a> {
    store: &'a mut SyncStore,
    servos: &'a mut [BusCounters; 256],
    start: Duration,
    /// Replies this round is waiting for.
    outstanding: usize,
    wrong: u64,
    /// Arrival of the last reply taken.
    finished_at: Option<Duration>,
    /// Servos whose reply to an earlier request is overdue: the first frame
    /// of one may be that late reply, so the round waits for a second.
    owed: [bool; 256],
    /// Servos of `owed` that sent two frames: the first was the late reply.
    late: [bool; 256],
}

impl Sink for Round<'_> {
    fn packet(&mut self, packet: &Packet<'_>, now: Duration) -> bool {
        let id = packet.id();
        let counters = &mut self.servos[usize::from(id)];
        let slot = match self.store.slot_of(id) {
            Some(i) if self.store.pending.contains(&id) => i,
            // Not asked in this round: another servo's, or a stray repeat.
            _ => {
                self.wrong += 1;
                counters.wrong_replies += 1;
                return false;
            }
        };
        let owed = self.owed[usize::from(id)];
        match self.store.slots[slot] {
            Slot::Missing(MissingReason::NoReply | MissingReason::Corrupt) => {}
            Slot::Answered(_) if owed && !self.late[usize::from(id)] => {
                // A servo answers in order: the frame before this one was
                // its late reply to an earlier request, and this is the
                // reply to this one.
                self.late[usize::from(id)] = true;
            }
            Slot::Answered(_) | Slot::Missing(MissingReason::WrongLength) => {
                // A second frame claiming the same ID: a servo sharing it, or
                // a misrouted reply. Which one is right cannot be known, so
                // neither is kept.
                self.store.slots[slot] = Slot::Missing(MissingReason::Ambiguous);
                self.outstanding += 1;
                self.wrong += 1;
                counters.wrong_replies += 1;
                return false;
            }
            Slot::Missing(MissingReason::Ambiguous) => {
                self.wrong += 1;
                counters.wrong_replies += 1;
                return false;
            }
        }
        // The first frame of an overdue servo is kept, but it may be its
        // late reply to an earlier request: it counts once no second frame
        // has come by the deadline. One round trip is recorded per servo
        // that answered, at its first frame.
        let provisional = owed && !self.late[usize::from(id)];
        let second = owed && !provisional;
        let len = self.store.len;
        let params = packet.params();
        if params.len() == len {
            self.store.data[slot * len..(slot + 1) * len].copy_from_slice(params);
            let flags = packet.status();
            self.store.slots[slot] = Slot::Answered(flags);
            if !second {
                counters.rtt.record(now.saturating_sub(self.start));
            }
            if provisional {
                return false;
            }
            if !flags.is_ok() {
                counters.status_errors += 1;
            }
        } else {
            self.store.slots[slot] = Slot::Missing(MissingReason::WrongLength);
            counters.wrong_replies += 1;
            self.wrong += 1;
        }
        self.finished_at = Some(now);
        self.outstanding = self.outstanding.saturating_sub(1);
        // Stop as soon as every servo asked has answered. When some are
        // missing the wait runs to the deadline, so that a second frame
        // claiming an ID already answered is seen and the ID marked
        // ambiguous rather than trusted.
        self.outstanding == 0
    }

    fn checksum_error(&mut self, id: u8) {
        if let Some(i) = self.store.slot_of(id) {
            self.servos[usize::from(id)].checksum_errors += 1;
            if let Slot::Missing(reason @ MissingReason::NoReply) = &mut self.store.slots[i] {
                *reason = MissingReason::Corrupt;
            }
        }
    }
}
impl<T: Transport> Bus<T> {
    /// SYNC READ `len` bytes at `address` from the servos `ids`, asking once.
    /// Every servo gets a result; see [`SyncRead`]. On SCS servos (no SYNC
    /// READ in their firmware) each servo is read in turn instead. Does not
    /// allocate once the storage has grown to the largest request seen.
    ///
    /// # Errors
    /// Only for the request as a whole: [`BusError::InvalidRequest`] (no IDs,
    /// `len` 0), [`BusError::DuplicateId`], [`BusError::IdOutOfRange`],
    /// [`BusError::NotAnswered`], [`BusError::Transport`]. Missing servos
    /// are not errors.
    pub fn sync_read(
        &mut self,
        address: u8,
        len: u8,
        ids: &[u8],
    ) -> Result<SyncRead<'_>, BusError> {
        self.sync_read_rounds(address, len, ids, None)
    }

    /// As [`Bus::sync_read`], then asks again only the servos still missing,
    /// up to [`BusSettings::retries`](crate::BusSettings::retries) times, as
    /// long as the whole re-ask fits within `budget` from the start of the
    /// first request.
    ///
    /// # Errors
    /// As [`Bus::sync_read`].
    pub fn sync_read_within(
        &mut self,
        address: u8,
        len: u8,
        ids: &[u8],
        budget: Duration,
    ) -> Result<SyncRead<'_>, BusError> {
        self.sync_read_rounds(address, len, ids, Some(budget))
    }

    /// As [`Bus::sync_read_within`], for reads that are not timed (finding
    /// the servos before a run): every reply timeout is
    /// [`PATIENCE`] longer than the settings make it, and the servos
    /// still missing are asked again until [`PATIENT_TRIES`] rounds
    /// have been made, so that a loaded host or a slow adapter does not
    /// make a present servo look absent. The settings are unchanged after.
    ///
    /// # Errors
    /// As [`Bus::sync_read`].
    pub fn sync_read_patiently(
        &mut self,
        address: u8,
        len: u8,
        ids: &[u8],
    ) -> Result<SyncRead<'_>, BusError> {
        let saved = self.settings;
        self.settings.link.latency += PATIENCE;
        self.settings.retries = PATIENT_TRIES - 1;
        let done = self
            .sync_read_rounds(address, len, ids, Some(Duration::MAX))
            .map(|_| ());
        self.settings = saved;
        done?;
        Ok(self.last_sync_read())
    }

    /// The results of the last SYNC READ.
    pub fn last_sync_read(&self) -> SyncRead<'_> {
        SyncRead { store: &self.sync }
    }

    fn sync_read_rounds(
        &mut self,
        address: u8,
        len: u8,
        ids: &[u8],
        budget: Option<Duration>,
    ) -> Result<SyncRead<'_>, BusError> {
        if ids.is_empty() || len == 0 {
            return Err(BusError::InvalidRequest("SYNC READ of nothing"));
        }
        self.sync.reset(address, usize::from(len), ids)?;
        self.counters.transactions += 1;
        for &id in ids {
            self.servos[usize::from(id)].transactions += 1;
        }
        let began = self.io.transport.clock().now();
        let mut round = 0u8;
        loop {
            self.sync_round()?;
            self.sync.collect_missing();
            if self.sync.pending.is_empty() {
                break;
            }
            let Some(budget) = budget else { break };
            if round >= self.settings.retries {
                break;
            }
            let next = self.round_timeout(self.sync.pending.len())?;
            if self.io.transport.clock().now() + next > began.saturating_add(budget) {
                break;
            }
            round += 1;
            self.counters.retries += 1;
            for &id in &self.sync.pending {
                self.servos[usize::from(id)].retries += 1;
            }
        }
        for &id in &self.sync.pending {
            self.servos[usize::from(id)].failures += 1;
        }
        self.counters.failures += self.sync.pending.len() as u64;
        Ok(SyncRead { store: &self.sync })
    }

    /// Deadline of a round asking `servos` servos: one SYNC READ, or on
    /// SCS servos one READ after another.
    fn round_timeout(&self, servos: usize) -> Result<Duration, BusError> {
        let s = &self.settings;
        let len = self.sync.len;
        let deadline = if s.series.has_sync_read() {
            let tx = Transaction::SyncRead { servos, len };
            self.link().deadline(tx, s.return_delay, s.replies)
        } else {
            let tx = Transaction::Read { len };
            let each = self.link().deadline(tx, s.return_delay, s.replies);
            each.map(|d| d * u32::try_from(servos).unwrap_or(u32::MAX))
        };
        deadline.ok_or(BusError::NotAnswered { level: s.replies })
    }

    /// Asks every servo in `sync.pending` once.
    fn sync_round(&mut self) -> Result<(), BusError> {
        for &id in &self.sync.pending {
            if let Some(i) = self.sync.slot_of(id) {
                self.sync.attempts[i] = self.sync.attempts[i].saturating_add(1);
                self.sync.slots[i] = Slot::Missing(MissingReason::NoReply);
            }
        }
        if !self.settings.series.has_sync_read() {
            return self.read_each();
        }
        let n = self.sync.pending.len();
        self.io.begin();
        self.io.tx_len = encode::sync_read(
            &mut self.io.tx,
            self.sync.address,
            self.sync.len as u8,
            &self.sync.pending,
        )?;
        let timeout = self.round_timeout(n)?;
        let start = self.send()?;
        let heard = self.io.heard();
        let mut sink = Round {
            store: &mut self.sync,
            servos: &mut self.servos,
            start,
            outstanding: n,
            wrong: 0,
            finished_at: None,
            owed: self.io.overdue_flags(),
            late: [false; 256],
        };
        let tally = self.io.exchange(start + timeout, &mut sink)?;
        let (wrong, finished_at, late, owed) = (sink.wrong, sink.finished_at, sink.late, sink.owed);
        for &id in &self.sync.pending {
            if late[usize::from(id)] {
                self.io.late_reply(id);
            }
        }
        self.count_late();
        // Per-servo checksum errors and wrong replies were counted by the
        // sink; the bus gets the totals.
        self.account(usize::from(BROADCAST_ID), &tally, wrong);
        let mut complete = true;
        for k in 0..self.sync.pending.len() {
            let id = self.sync.pending[k];
            let Some(i) = self.sync.slot_of(id) else {
                continue;
            };
            match self.sync.slots[i] {
                Slot::Answered(flags) => {
                    self.sync.sampled[i] = heard;
                    let in_doubt = owed[usize::from(id)] && !late[usize::from(id)];
                    self.sync.in_doubt[i] = in_doubt;
                    if in_doubt {
                        self.io.answered_in_doubt(id);
                    } else {
                        self.io.answered(id);
                    }
                    if !flags.is_ok() {
                        self.counters.status_errors += 1;
                    }
                }
                Slot::Missing(reason) => {
                    complete = false;
                    if reason == MissingReason::NoReply {
                        self.timed_out(id);
                    }
                }
            }
        }
        if let (true, Some(at)) = (complete, finished_at) {
            self.counters.rtt.record(at.saturating_sub(start));
        }
        Ok(())
    }

    /// The SCS fallback: one READ per pending servo, no retries inside.
    fn read_each(&mut self) -> Result<(), BusError> {
        let saved = self.settings.retries;
        self.settings.retries = 0;
        let mut buf = [0u8; MAX_PARAMS];
        let len = self.sync.len;
        let mut result = Ok(());
        for k in 0..self.sync.pending.len() {
            let id = self.sync.pending[k];
            let Some(i) = self.sync.slot_of(id) else {
                continue;
            };
            match self.read(id, self.sync.address, &mut buf[..len]) {
                Ok(flags) => {
                    self.sync.data[i * len..(i + 1) * len].copy_from_slice(&buf[..len]);
                    self.sync.slots[i] = Slot::Answered(flags);
                    self.sync.sampled[i] = self.io.heard();
                    self.sync.in_doubt[i] = false;
                }
                Err(BusError::Corrupt { .. }) => {
                    self.sync.slots[i] = Slot::Missing(MissingReason::Corrupt);
                }
                Err(BusError::WrongLength { .. }) => {
                    self.sync.slots[i] = Slot::Missing(MissingReason::WrongLength);
                }
                Err(e) if e.is_retryable() => {}
                Err(e) => {
                    result = Err(e);
                    break;
                }
            }
        }
        self.settings.retries = saved;
        result
    }
}
