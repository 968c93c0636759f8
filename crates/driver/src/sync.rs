//! SYNC WRITE and SYNC READ: one request for many servos, results per servo.
//!
//! A SYNC READ never fails as a whole because one servo did not answer: each
//! servo gets its own outcome, the answers that came are kept, and the
//! missing ones say why. Replies are matched to servos by ID only (a reply
//! from an ID not asked, or a second reply from one that already answered,
//! is counted and dropped), so no data is ever attributed to the wrong servo.
//!
//! Results live in storage owned by the bus and reused from call to call;
//! [`SyncRead`] borrows it.

use std::time::Duration;

use servobus_protocol::{encode, Packet, StatusFlags, BROADCAST_ID, MAX_PARAMS};
use servobus_timing::{pack_sync_write, servos_per_frame, Block, PackError, Transaction};

use crate::io::Sink;
use crate::stats::Counters;
use crate::{Bus, BusError, Clock, Transport};

const NO_SLOT: u8 = u8::MAX;

/// Added to every reply timeout by [`Bus::sync_read_patiently`].
pub const PATIENCE: Duration = Duration::from_millis(100);
/// Rounds [`Bus::sync_read_patiently`] makes before a servo counts as
/// missing.
pub const PATIENT_TRIES: u8 = 3;

/// Why a servo is missing from a SYNC READ result.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum MissingReason {
    /// Nothing from it arrived before the deadline.
    NoReply,
    /// A frame with its ID arrived with a bad checksum.
    Corrupt,
    /// Its reply carried the wrong number of data bytes.
    WrongLength,
    /// Two valid frames claimed its ID (two servos sharing it, or a reply
    /// misrouted): neither is trusted.
    Ambiguous,
}

impl std::fmt::Display for MissingReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            MissingReason::NoReply => "no reply",
            MissingReason::Corrupt => "corrupted reply",
            MissingReason::WrongLength => "reply of the wrong length",
            MissingReason::Ambiguous => "two replies claimed its ID",
        })
    }
}

/// A servo that answered a SYNC READ.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SyncReply<'a> {
    /// Its ID.
    pub id: u8,
    /// Its status byte.
    pub flags: StatusFlags,
    /// The bytes read, in the bus's byte order.
    pub data: &'a [u8],
}

/// A servo missing from a SYNC READ result.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Missing {
    /// Its ID.
    pub id: u8,
    /// Why, at the last attempt.
    pub reason: MissingReason,
    /// How many times it was asked.
    pub attempts: u8,
}

#[derive(Debug, Clone, Copy)]
enum Slot {
    Missing(MissingReason),
    Answered(StatusFlags),
}

/// Reused storage of the last SYNC READ.
#[derive(Debug)]
pub(crate) struct SyncStore {
    address: u8,
    len: usize,
    /// IDs in request order.
    ids: Vec<u8>,
    slots: Vec<Slot>,
    attempts: Vec<u8>,
    /// `ids.len() * len` bytes; servo `i`'s data at `i * len`.
    data: Vec<u8>,
    /// Position in `ids` of each ID, or `NO_SLOT`.
    index: [u8; 256],
    /// The IDs asked in the current round.
    pending: Vec<u8>,
}

impl SyncStore {
    pub fn new() -> Self {
        // Room for every servo a bus can hold with 8-byte reads, so that
        // ordinary control loops never grow it.
        SyncStore {
            address: 0,
            len: 0,
            ids: Vec::with_capacity(254),
            slots: Vec::with_capacity(254),
            attempts: Vec::with_capacity(254),
            data: Vec::with_capacity(254 * 8),
            index: [NO_SLOT; 256],
            pending: Vec::with_capacity(254),
        }
    }

    fn reset(&mut self, address: u8, len: usize, ids: &[u8]) -> Result<(), BusError> {
        for &id in &self.ids {
            self.index[usize::from(id)] = NO_SLOT;
        }
        self.ids.clear();
        self.address = address;
        self.len = len;
        for (i, &id) in ids.iter().enumerate() {
            let problem = if id > servobus_protocol::MAX_ID {
                Some("SYNC READ of an ID above 253")
            } else if self.index[usize::from(id)] != NO_SLOT {
                Some("an ID appears twice in a SYNC READ")
            } else {
                None
            };
            if let Some(problem) = problem {
                // Leave the store empty and its index clean.
                for &id in &self.ids {
                    self.index[usize::from(id)] = NO_SLOT;
                }
                self.ids.clear();
                self.slots.clear();
                self.attempts.clear();
                self.data.clear();
                self.pending.clear();
                return Err(BusError::InvalidRequest(problem));
            }
            // `i < 254` because the IDs are distinct and at most 253.
            self.index[usize::from(id)] = i as u8;
            self.ids.push(id);
        }
        self.slots.clear();
        self.slots
            .resize(ids.len(), Slot::Missing(MissingReason::NoReply));
        self.attempts.clear();
        self.attempts.resize(ids.len(), 0);
        self.data.clear();
        self.data.resize(ids.len() * len, 0);
        self.pending.clear();
        self.pending.extend_from_slice(ids);
        Ok(())
    }

    fn slot_of(&self, id: u8) -> Option<usize> {
        let i = self.index[usize::from(id)];
        (i != NO_SLOT).then_some(usize::from(i))
    }

    /// Collects the IDs still missing into `pending`.
    fn collect_missing(&mut self) {
        self.pending.clear();
        for (i, slot) in self.slots.iter().enumerate() {
            if matches!(slot, Slot::Missing(_)) {
                self.pending.push(self.ids[i]);
            }
        }
    }
}

/// Results of the last SYNC READ, one per servo in request order.
#[derive(Debug, Clone, Copy)]
pub struct SyncRead<'a> {
    store: &'a SyncStore,
}

impl<'a> SyncRead<'a> {
    /// Number of servos asked.
    pub fn len(&self) -> usize {
        self.store.ids.len()
    }

    /// Whether no servo was asked.
    pub fn is_empty(&self) -> bool {
        self.store.ids.is_empty()
    }

    /// The first address read.
    pub fn address(&self) -> u8 {
        self.store.address
    }

    /// Bytes read from each servo.
    pub fn data_len(&self) -> usize {
        self.store.len
    }

    /// The result of the `index`-th servo of the request.
    pub fn get(&self, index: usize) -> Option<Result<SyncReply<'a>, Missing>> {
        let store = self.store;
        let id = *store.ids.get(index)?;
        Some(match store.slots[index] {
            Slot::Answered(flags) => Ok(SyncReply {
                id,
                flags,
                data: &store.data[index * store.len..(index + 1) * store.len],
            }),
            Slot::Missing(reason) => Err(Missing {
                id,
                reason,
                attempts: store.attempts[index],
            }),
        })
    }

    /// The result of servo `id`, if it was asked.
    pub fn by_id(&self, id: u8) -> Option<Result<SyncReply<'a>, Missing>> {
        self.store.slot_of(id).and_then(|i| self.get(i))
    }

    /// Every result, in request order.
    pub fn iter(&self) -> impl Iterator<Item = Result<SyncReply<'a>, Missing>> + 'a {
        let this = *self;
        (0..this.len()).filter_map(move |i| this.get(i))
    }

    /// How many servos answered.
    pub fn answered(&self) -> usize {
        self.store
            .slots
            .iter()
            .filter(|s| matches!(s, Slot::Answered(_)))
            .count()
    }

    /// How many servos are missing.
    pub fn missing(&self) -> usize {
        self.len() - self.answered()
    }

    /// Whether every servo answered.
    pub fn is_complete(&self) -> bool {
        self.missing() == 0
    }
}

/// Collects the replies of one SYNC READ round.
struct Round<'a> {
    store: &'a mut SyncStore,
    servos: &'a mut [Counters; 256],
    start: Duration,
    /// Replies this round is waiting for.
    outstanding: usize,
    wrong: u64,
    /// Arrival of the last reply taken.
    finished_at: Option<Duration>,
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
        match self.store.slots[slot] {
            Slot::Missing(MissingReason::NoReply | MissingReason::Corrupt) => {}
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
        let len = self.store.len;
        let params = packet.params();
        if params.len() == len {
            self.store.data[slot * len..(slot + 1) * len].copy_from_slice(params);
            let flags = packet.status();
            self.store.slots[slot] = Slot::Answered(flags);
            counters.rtt.record(now.saturating_sub(self.start));
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

impl<T: Transport, C: Clock> Bus<T, C> {
    /// SYNC WRITE `data` at `address` to the servos `ids`: servo `ids[i]`
    /// gets `data[i * L..(i + 1) * L]` with `L = data.len() / ids.len()`.
    /// Nobody answers. The frames are packed by
    /// [`servobus_timing::pack_sync_write`] (split where the length byte
    /// would pass 255), the same packer the cycle budget and the benches
    /// measure. Does not allocate for a single frame (up to 35 servos with
    /// 6-byte blocks), nor for more once the bus has sent as many.
    ///
    /// # Errors
    /// [`BusError::InvalidRequest`] when `data` is not `ids.len()` blocks of
    /// 1..=250 bytes; [`BusError::Encode`] for an invalid ID;
    /// [`BusError::Transport`].
    pub fn sync_write(&mut self, address: u8, ids: &[u8], data: &[u8]) -> Result<(), BusError> {
        if ids.is_empty() || data.is_empty() || data.len() % ids.len() != 0 {
            return Err(BusError::InvalidRequest(
                "SYNC WRITE data must be one equal block per servo",
            ));
        }
        let len = u8::try_from(data.len() / ids.len())
            .map_err(|_| BusError::InvalidRequest("SYNC WRITE block too long"))?;
        let block = Block::new(address, len);
        self.io.begin();
        // The usual case, one frame: packed straight into the send buffer.
        match pack_sync_write(&mut self.io.tx, block, ids, data) {
            Ok(packed) => {
                self.io.tx_len = packed.len;
                self.count_sync_write(ids);
                self.io.send()?;
                return Ok(());
            }
            Err(PackError::BufferTooSmall { needed, .. }) => {
                if self.packed.len() < needed {
                    self.packed.resize(needed, 0);
                }
            }
            Err(e) => return Err(pack_error(e)),
        }
        let packed = pack_sync_write(&mut self.packed, block, ids, data).map_err(pack_error)?;
        let per_frame = servos_per_frame(len);
        for i in 0..packed.frames {
            if i > 0 {
                self.io.begin();
            }
            let Some(range) = packed.frame_range(i) else {
                break;
            };
            let frame_len = range.len();
            self.io.tx[..frame_len].copy_from_slice(&self.packed[range]);
            self.io.tx_len = frame_len;
            let first = i * per_frame;
            self.count_sync_write(&ids[first..ids.len().min(first + per_frame)]);
            self.io.send()?;
        }
        Ok(())
    }

    /// Counts one SYNC WRITE frame to `ids`.
    fn count_sync_write(&mut self, ids: &[u8]) {
        self.counters.transactions += 1;
        for &id in ids {
            self.servos[usize::from(id)].transactions += 1;
        }
    }

    /// Sends a frame encoded by the caller (e.g. a SYNC WRITE packed by
    /// `servobus-timing`) and waits for no reply.
    ///
    /// # Errors
    /// [`BusError::InvalidRequest`] for a frame longer than any valid one;
    /// [`BusError::Transport`].
    pub fn send_frame(&mut self, frame: &[u8]) -> Result<(), BusError> {
        self.io.begin();
        let dst = self
            .io
            .tx
            .get_mut(..frame.len())
            .ok_or(BusError::InvalidRequest(
                "frame longer than any valid frame",
            ))?;
        dst.copy_from_slice(frame);
        self.io.tx_len = frame.len();
        self.counters.transactions += 1;
        self.io.send()?;
        Ok(())
    }

    /// SYNC READ `len` bytes at `address` from the servos `ids`, asking once.
    /// Every servo gets a result; see [`SyncRead`]. On SCS servos (no SYNC
    /// READ in their firmware) each servo is read in turn instead. Does not
    /// allocate once the storage has grown to the largest request seen.
    ///
    /// # Errors
    /// Only for the request as a whole: [`BusError::InvalidRequest`] (no IDs,
    /// a repeated ID, `len` 0), [`BusError::Transport`]. Missing servos are
    /// not errors.
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
        let began = self.io.clock.now();
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
            if self.io.clock.now() + next > began.saturating_add(budget) {
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
            s.link.deadline(tx, s.return_delay, s.replies)
        } else {
            let tx = Transaction::Read { len };
            let each = s.link.deadline(tx, s.return_delay, s.replies);
            each.map(|d| d * u32::try_from(servos).unwrap_or(u32::MAX))
        };
        deadline.ok_or(BusError::InvalidRequest(
            "the servos' status level does not answer reads",
        ))
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
        let start = self.io.send()?;
        let mut sink = Round {
            store: &mut self.sync,
            servos: &mut self.servos,
            start,
            outstanding: n,
            wrong: 0,
            finished_at: None,
        };
        let tally = self.io.exchange(start + timeout, &mut sink)?;
        let (wrong, finished_at) = (sink.wrong, sink.finished_at);
        // Per-servo checksum errors and wrong replies were counted by the
        // sink; the bus gets the totals.
        self.account(usize::from(BROADCAST_ID), &tally, wrong);
        let mut complete = true;
        for &id in &self.sync.pending {
            let Some(i) = self.sync.slot_of(id) else {
                continue;
            };
            match self.sync.slots[i] {
                Slot::Answered(flags) => {
                    if !flags.is_ok() {
                        self.counters.status_errors += 1;
                    }
                }
                Slot::Missing(reason) => {
                    complete = false;
                    if reason == MissingReason::NoReply {
                        self.counters.timeouts += 1;
                        self.servos[usize::from(id)].timeouts += 1;
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

/// The bus error for a packing failure (the arguments were checked first,
/// so only an invalid ID or an impossible block remains).
fn pack_error(e: PackError) -> BusError {
    match e {
        PackError::Encode(e) => BusError::Encode(e),
        _ => BusError::InvalidRequest("SYNC WRITE block too long"),
    }
}
