//! Reading the joints' positions back: patiently at start-up (every servo
//! must answer), then each cycle the servos the timing plan schedules,
//! within what is left of the cycle.
//!
//! On a bus with wheel joints every read takes the present speed too
//! (register `present_speed`, 58, sign-magnitude steps/s, right after the
//! present position: one read of 4 bytes from 56), which is what a wheel
//! is tracked by; a bus of position joints alone reads the position only.

use std::ops::Range;
use std::time::Duration;

use servobus_driver::{Bus, Clock, MissingReason, Transport};
use servobus_protocol::registers::{ByteOrder, Register};

use super::tracking::{Reading, Tracker};
use crate::error::{PortGone, RunError};

/// The position register of one bus's servos and their IDs.
#[derive(Debug)]
pub(crate) struct Feedback {
    reg: &'static Register,
    /// The speed register, read with the position (buses with wheels).
    speed: Option<&'static Register>,
    order: ByteOrder,
    ids: Vec<u8>,
}

impl Feedback {
    /// Reads `reg` of the servos `ids`, and `speed` with it when given
    /// (it must follow `reg` directly).
    pub fn new(
        reg: &'static Register,
        speed: Option<&'static Register>,
        order: ByteOrder,
        ids: Vec<u8>,
    ) -> Self {
        let speed = speed.filter(|s| u16::from(s.address) == reg.end());
        Feedback {
            reg,
            speed,
            order,
            ids,
        }
    }

    /// Bytes of one servo's reply as `u8` (position, and speed).
    fn len(&self) -> u8 {
        self.reg.size + self.speed.map_or(0, |s| s.size)
    }

    /// The reading in `data` (one servo's reply): position ticks, and
    /// speed in steps/s when read; `None` when it does not decode.
    fn decode(&self, data: &[u8]) -> Option<(i32, Option<i32>)> {
        let (p, s) = data.split_at_checked(usize::from(self.reg.size))?;
        let ticks = self.reg.decode(p, self.order).ok()?;
        let speed = match self.speed {
            Some(reg) => Some(reg.decode(s, self.order).ok()?),
            None => None,
        };
        Some((ticks, speed))
    }

    /// The servos' IDs, in bus order.
    pub fn ids(&self) -> &[u8] {
        &self.ids
    }

    /// Bytes read of each servo (the position register, and the speed's).
    pub fn size(&self) -> usize {
        usize::from(self.len())
    }

    /// Reads every servo's position patiently (start-up is not timed; see
    /// [`Bus::sync_read_patiently`]) into `track`.
    ///
    /// # Errors
    ///
    /// [`RunError::Startup`] when the bus fails, [`RunError::NoServo`] naming
    /// the first servo that gave no position.
    pub fn startup<T: Transport>(
        &self,
        bus: &mut Bus<T>,
        name: &str,
        track: &mut Tracker,
    ) -> Result<(), RunError> {
        let read = bus
            .sync_read_patiently(self.reg.address, self.len(), &self.ids)
            .map_err(|source| RunError::Startup {
                bus: name.to_owned(),
                what: "reading the start positions",
                source,
            })?;
        for (i, r) in read.iter().enumerate() {
            let reason = match r {
                Ok(reply) => match self.decode(reply.data) {
                    Some((ticks, speed)) => {
                        let flags = servobus_protocol::StatusFlags(0);
                        let at = reply.sampled;
                        track.observe(
                            i,
                            Reading {
                                ticks,
                                speed,
                                at,
                                flags,
                            },
                        );
                        continue;
                    }
                    None => "it reported an impossible position".to_owned(),
                },
                Err(m) => m.reason.to_string(),
            };
            let j = &track.joints[i];
            return Err(RunError::NoServo {
                bus: name.to_owned(),
                id: j.id,
                joint: j.name.clone(),
                reason,
            });
        }
        Ok(())
    }

    /// Reads the servos `range` (indices in the bus) within `budget` into
    /// `track`; true when every servo answered in time. Only a lost port is
    /// an error: a silent servo is tracking's business.
    ///
    /// Each reading is stamped with the time the servo took it (when it had
    /// heard the request, [`SyncReply::sampled`](servobus_driver::SyncReply::sampled)),
    /// not when this thread decoded it: a host descheduled after the reply
    /// came must not compare the reading with a later point of the path.
    /// A reply that may be a late one to the cycle before
    /// ([`SyncReply::in_doubt`](servobus_driver::SyncReply::in_doubt)) is
    /// not used: which time its position is of cannot be told.
    pub fn read<T: Transport>(
        &self,
        bus: &mut Bus<T>,
        clock: &T::Clock,
        range: Range<usize>,
        budget: Duration,
        track: &mut Tracker,
    ) -> Result<bool, PortGone> {
        let Some(ids) = self.ids.get(range.clone()) else {
            return Ok(true);
        };
        let Some(read) =
            PortGone::check(bus.sync_read_within(self.reg.address, self.len(), ids, budget))?
        else {
            return Ok(false);
        };
        let now = clock.now();
        // Every servo of the bus silent in one read is the link's silence,
        // judged over time (see `Tracker::bus_silent`). A read of only some
        // of them (round robin) or of a lone servo says nothing about the
        // link: its silent servos are counted one by one.
        let whole_bus = ids.len() >= 2 && ids.len() == self.ids.len();
        let silent = || {
            read.iter()
                .all(|r| matches!(r, Err(m) if m.reason == MissingReason::NoReply))
        };
        if whole_bus && silent() {
            track.bus_silent(now);
            return Ok(false);
        }
        let mut all = true;
        for (i, r) in read.iter().enumerate() {
            let joint = range.start + i;
            match r {
                Ok(reply) if reply.in_doubt => {}
                Ok(reply) => match self.decode(reply.data) {
                    Some((ticks, speed)) => track.observe(
                        joint,
                        Reading {
                            ticks,
                            speed,
                            at: reply.sampled,
                            flags: reply.flags,
                        },
                    ),
                    None => track.miss(joint, None),
                },
                Err(m) => {
                    all = false;
                    track.miss(joint, Some(m.reason));
                }
            }
        }
        Ok(all)
    }
}
