//! `--fix`: the writes that repair what the checks found. EEPROM registers
//! are written with unlock-write-verify-lock; a baud-rate change is the same
//! transaction split across the two rates.

use servobus_driver::{Bus, BusError, Clock, StatusLevel, Transport, PATIENCE, PATIENT_TRIES};
use servobus_protocol::registers::addr;

use super::probe::{switch, MAX_RETURN_DELAY};
use super::{Action, BaudSwitch, Finding};

/// What became of one fix.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FixOutcome {
    /// The servo.
    pub id: u8,
    /// The command the fix stands for.
    pub command: String,
    /// `Err` with the reason when it failed.
    pub result: Result<(), String>,
}

/// Applies the fix of every fixable finding, servos at another baud rate
/// first (so the others can reach them) and the EEPROM lock last. The bus's
/// settings are left as they were.
///
/// # Errors
/// Only when the transport fails; a fix that fails is an outcome.
pub fn apply<T: Transport + BaudSwitch, C: Clock>(
    bus: &mut Bus<T, C>,
    findings: &[Finding],
) -> Result<Vec<FixOutcome>, BusError> {
    let saved = *bus.settings();
    let mut todo: Vec<&Finding> = findings.iter().filter(|f| f.fixable()).collect();
    todo.sort_by_key(|f| match f.action {
        Some(Action::Baud { .. }) => 0,
        Some(Action::Write { register, .. }) if register.name == "lock" => 2,
        _ => 1,
    });
    let mut out = Vec::new();
    for f in todo {
        let Some(action) = f.action else { continue };
        // Patient, as the examination: a write must not fail on a slow reply.
        bus.set_settings(
            saved
                .with_return_delay(MAX_RETURN_DELAY)
                .with_latency(saved.link.latency + PATIENCE)
                .with_retries(PATIENT_TRIES - 1),
        );
        let (id, result) = match action {
            Action::Write {
                id,
                register,
                value,
                silent,
                series,
            } => {
                let mut s = *bus.settings();
                if silent {
                    s.replies = StatusLevel::PingAndRead;
                }
                // The register's layout and the lock are the servo's series'.
                s.series = series;
                bus.set_settings(s);
                (id, bus.write_register(id, register, value).map(|_| ()))
            }
            Action::Baud { id, baud, index } => {
                (id, change_baud(bus, id, baud, index, saved.link.baud))
            }
        };
        match result {
            Err(BusError::Transport(e)) => {
                bus.set_settings(saved);
                return Err(BusError::Transport(e));
            }
            r => out.push(FixOutcome {
                id,
                command: f.fix.clone(),
                result: r.map_err(|e| e.to_string()),
            }),
        }
    }
    bus.set_settings(saved);
    Ok(out)
}

/// Unlocks servo `id` at `baud`, writes the bus's baud-rate index, then
/// reads it back and locks again at the bus's rate `home`.
fn change_baud<T: Transport + BaudSwitch, C: Clock>(
    bus: &mut Bus<T, C>,
    id: u8,
    baud: u32,
    index: u8,
    home: u32,
) -> Result<(), BusError> {
    let lock = bus.settings().series.map().lock_address;
    switch(bus, baud)?;
    let unlocked = bus.write(id, lock, &[0]);
    let written = unlocked.and_then(|_| match bus.write(id, addr::BAUD_RATE, &[index]) {
        // The servo may switch before its reply leaves: the read-back at
        // the new rate decides.
        Err(e) if e.is_retryable() => Ok(None),
        other => other,
    });
    switch(bus, home)?;
    written?;
    let mut back = [0u8; 1];
    let verified = bus.read(id, addr::BAUD_RATE, &mut back).and_then(|_| {
        if back[0] == index {
            Ok(())
        } else {
            Err(BusError::Verify {
                id,
                address: addr::BAUD_RATE,
                expected: vec![index],
                actual: back.to_vec(),
            })
        }
    });
    // Lock again at whichever rate the servo now hears.
    if bus.write(id, lock, &[1]).is_err() {
        switch(bus, baud)?;
        let _ = bus.write(id, lock, &[1]);
        switch(bus, home)?;
    }
    verified
}
