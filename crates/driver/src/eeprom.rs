//! Persistent (EEPROM) writes as one transaction: unlock, write, read back
//! and verify, lock again.
//!
//! The lock register (55 on STS/SMS, 48 on SCS) decides whether EEPROM
//! writes survive a power cycle; a write applies at once either way. So the
//! transaction opens the lock, writes, checks the servo now holds the bytes,
//! and closes the lock — at the new ID when the ID register itself was
//! written. The servo answers the ID write from its old ID (STS firmware);
//! a reply from either ID is accepted.
//!
//! A transaction is a critical section: SIGINT, SIGTERM and SIGHUP that
//! come during it are held until the servo is locked again
//! ([`SignalHold`]). [`Bus::write_eeprom_all`] writes several registers of
//! one servo as one transaction, and puts back the bytes it found when a
//! step fails, so that a servo is left fully written or as it was.

use servobus_protocol::registers::addr;
use servobus_protocol::{StatusFlags, MAX_PARAMS};

use crate::{Bus, BusError, SignalHold, Transport};

/// The outcome of [`Bus::write_eeprom`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EepromWrite {
    /// The servo's ID afterwards (the new one when the ID was written).
    pub id: u8,
    /// Status flags of the verifying read.
    pub flags: StatusFlags,
}

impl<T: Transport> Bus<T> {
    /// Writes `data` at `address` of servo `id` so that it persists:
    /// unlock, write, read back and compare, lock. When the write covers the
    /// ID register, the read-back and the lock go to the new ID.
    ///
    /// If any step after the unlock fails, the lock is closed again (best
    /// effort, at whichever ID answers) before the error is returned.
    /// SIGINT, SIGTERM and SIGHUP are held from the unlock until the lock
    /// ([`SignalHold`]).
    ///
    /// # Errors
    /// [`BusError::Verify`] when the servo reads back other bytes; the error
    /// of the first step that failed otherwise.
    pub fn write_eeprom(
        &mut self,
        id: u8,
        address: u8,
        data: &[u8],
    ) -> Result<EepromWrite, BusError> {
        if data.is_empty() || data.len() > MAX_PARAMS - 1 {
            return Err(BusError::InvalidRequest(
                "EEPROM write of no or too many bytes",
            ));
        }
        let lock = self.settings.series.map().lock_address;
        // Where the ID register falls inside the written range, if it does.
        let new_id = usize::from(addr::ID)
            .checked_sub(usize::from(address))
            .and_then(|at| data.get(at).copied())
            .unwrap_or(id);
        if new_id > servobus_protocol::MAX_ID {
            return Err(BusError::IdOutOfRange { id: new_id });
        }
        let _hold = SignalHold::new();
        self.write(id, lock, &[0])?;
        match self.write_verify(id, new_id, address, data) {
            Ok(flags) => {
                self.write(new_id, lock, &[1])?;
                Ok(EepromWrite { id: new_id, flags })
            }
            Err(e) => {
                // Best effort: the first error is the one worth reporting.
                if self.write(new_id, lock, &[1]).is_err() && new_id != id {
                    let _ = self.write(id, lock, &[1]);
                }
                Err(e)
            }
        }
    }

    /// Writes every `(address, bytes)` of `changes` to servo `id` as one
    /// persistent transaction: the bytes there are read first, then the
    /// lock is opened, each change written and read back, and the lock
    /// closed. When a step fails, what was written is put back (and read
    /// back) before the lock closes, so the servo holds either every change
    /// or none. SIGINT, SIGTERM and SIGHUP are held from the first read
    /// until the lock ([`SignalHold`]). The ID register cannot be among
    /// the changes: [`Bus::write_eeprom`] changes an ID.
    ///
    /// # Errors
    /// [`BusError::InvalidRequest`] for an empty change, one of too many
    /// bytes or one that covers the ID; [`BusError::Verify`] when the servo
    /// reads back other bytes; the error of the first step that failed
    /// otherwise (the servo then holds its old bytes, unless putting them
    /// back failed too).
    pub fn write_eeprom_all(
        &mut self,
        id: u8,
        changes: &[(u8, &[u8])],
    ) -> Result<EepromWrite, BusError> {
        for &(address, data) in changes {
            if data.is_empty() || data.len() > MAX_PARAMS - 1 {
                return Err(BusError::InvalidRequest(
                    "EEPROM write of no or too many bytes",
                ));
            }
            let end = usize::from(address) + data.len();
            if (usize::from(address)..end).contains(&usize::from(addr::ID)) {
                return Err(BusError::InvalidRequest(
                    "an ID change is a transaction of its own (write_eeprom)",
                ));
            }
        }
        let lock = self.settings.series.map().lock_address;
        let _hold = SignalHold::new();
        // What the servo holds now, to put back if a step fails.
        let mut before = Vec::with_capacity(changes.len());
        for &(address, data) in changes {
            let mut old = vec![0u8; data.len()];
            self.read(id, address, &mut old)?;
            before.push(old);
        }
        self.write(id, lock, &[0])?;
        let mut flags = StatusFlags(0);
        let mut done = 0;
        let mut failed = None;
        for &(address, data) in changes {
            match self.write_verify(id, id, address, data) {
                Ok(f) => {
                    flags = f;
                    done += 1;
                }
                Err(e) => {
                    failed = Some(e);
                    break;
                }
            }
        }
        let Some(error) = failed else {
            self.write(id, lock, &[1])?;
            return Ok(EepromWrite { id, flags });
        };
        // The failed change may have been taken before its reply was lost:
        // it is put back with the ones before it, newest first.
        let tried = (done + 1).min(changes.len());
        for (&(address, _), old) in changes[..tried].iter().zip(&before).rev() {
            let _ = self.write_verify(id, id, address, old);
        }
        let _ = self.write(id, lock, &[1]);
        Err(error)
    }

    fn write_verify(
        &mut self,
        id: u8,
        new_id: u8,
        address: u8,
        data: &[u8],
    ) -> Result<StatusFlags, BusError> {
        match self.write_either(id, new_id, address, data) {
            Ok(_) => {}
            // The servo may have taken the new ID and its reply been lost:
            // the read-back at the new ID decides.
            Err(e) if new_id != id && e.is_retryable() => {}
            Err(e) => return Err(e),
        }
        let mut back = [0u8; MAX_PARAMS];
        let back = &mut back[..data.len()];
        let flags = self.read(new_id, address, back)?;
        if back != data {
            return Err(BusError::Verify {
                id: new_id,
                address,
                expected: data.to_vec(),
                actual: back.to_vec(),
            });
        }
        Ok(flags)
    }
}
