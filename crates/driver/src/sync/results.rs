//! The results of a SYNC READ: one per servo, kept in storage the bus reuses.

use std::time::Duration;

use servobus_protocol::StatusFlags;

use crate::BusError;

const NO_SLOT: u8 = u8::MAX;

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
    /// When the servo took the reading, on the bus's clock: when it had
    /// heard the request it answered ([`Bus::heard`](crate::Bus::heard)),
    /// not when the host read the reply.
    pub sampled: Duration,
    /// The servo's reply to an earlier request was overdue, and this round
    /// brought one frame from it: that frame may be the late reply (one
    /// request older) or the answer, which cannot be told apart. Its data
    /// are the servo's, but of one of two times.
    pub in_doubt: bool,
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
pub(super) enum Slot {
    Missing(MissingReason),
    Answered(StatusFlags),
}

/// Reused storage of the last SYNC READ.
#[derive(Debug)]
pub(crate) struct SyncStore {
    pub(super) address: u8,
    pub(super) len: usize,
    /// IDs in request order.
    pub(super) ids: Vec<u8>,
    pub(super) slots: Vec<Slot>,
    pub(super) attempts: Vec<u8>,
    /// When each servo took its reading (see [`SyncReply::sampled`]).
    pub(super) sampled: Vec<Duration>,
    /// Whether each answer is in doubt (see [`SyncReply::in_doubt`]).
    pub(super) in_doubt: Vec<bool>,
    /// `ids.len() * len` bytes; servo `i`'s data at `i * len`.
    pub(super) data: Vec<u8>,
    /// Position in `ids` of each ID, or `NO_SLOT`.
    pub(super) index: [u8; 256],
    /// The IDs asked in the current round.
    pub(super) pending: Vec<u8>,
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
            sampled: Vec::with_capacity(254),
            in_doubt: Vec::with_capacity(254),
            data: Vec::with_capacity(254 * 8),
            index: [NO_SLOT; 256],
            pending: Vec::with_capacity(254),
        }
    }

    pub(super) fn reset(&mut self, address: u8, len: usize, ids: &[u8]) -> Result<(), BusError> {
        for &id in &self.ids {
            self.index[usize::from(id)] = NO_SLOT;
        }
        self.ids.clear();
        self.address = address;
        self.len = len;
        for (i, &id) in ids.iter().enumerate() {
            let problem = if id > servobus_protocol::MAX_ID {
                Some(BusError::IdOutOfRange { id })
            } else if self.index[usize::from(id)] != NO_SLOT {
                Some(BusError::DuplicateId { id })
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
                self.sampled.clear();
                self.in_doubt.clear();
                self.data.clear();
                self.pending.clear();
                return Err(problem);
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
        self.sampled.clear();
        self.sampled.resize(ids.len(), Duration::ZERO);
        self.in_doubt.clear();
        self.in_doubt.resize(ids.len(), false);
        self.data.clear();
        self.data.resize(ids.len() * len, 0);
        self.pending.clear();
        self.pending.extend_from_slice(ids);
        Ok(())
    }

    pub(super) fn slot_of(&self, id: u8) -> Option<usize> {
        let i = self.index[usize::from(id)];
        (i != NO_SLOT).then_some(usize::from(i))
    }

    /// Collects the IDs still missing into `pending`.
    pub(super) fn collect_missing(&mut self) {
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
    pub(super) store: &'a SyncStore,
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
                sampled: store.sampled[index],
                in_doubt: store.in_doubt[index],
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
