//! Applying fixes: the writes that repair what the checks found. EEPROM registers
//! are written with unlock-write-verify-lock; a baud-rate change is the same
//! transaction split across the two rates. Homing offsets are set for the
//! session, as play sets them (lock closed: nothing persists), unless
//! [`Fixing::write_servos`] asks for EEPROM; what the robot file asks of the
//! servos' EEPROM (an operating mode, a `servo:` setting) is stored only
//! then, an operating mode with the torque turned off first.

use servobus_driver::{
    stop_signal, Bus, BusError, StatusLevel, StopSignal, Transport, PATIENCE, PATIENT_TRIES,
};
use servobus_protocol::registers::addr;

use crate::calibrate::{prepare_bus, Refusal};
use servobus_protocol::registers::{Register, Series};

use super::probe::MAX_RETURN_DELAY;
use super::{Action, Advice, Finding, Fixing};

/// Why a fix failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FixError {
    /// The write, or its check, failed on the bus.
    #[error(transparent)]
    Bus(#[from] BusError),
    /// Play's calibration check refused the robot, so the session's homing
    /// offsets were not set.
    #[error(transparent)]
    Refused(Refusal),
    /// Not applied: the program caught a stop signal before this fix began
    /// (the fix under way was finished first).
    #[error("not applied: stopped by {0}")]
    Stopped(StopSignal),
}

/// What a fix did.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum Applied {
    /// What a finding advised (a write, a baud-rate change: its
    /// [`Advice::Run`]).
    Advice(Advice),
    /// Homing offset `value` stored in EEPROM.
    OffsetStored(i32),
    /// Homing offset `value` set for this session, as play sets it.
    OffsetForSession(i32),
    /// What the robot file asks of a register stored in EEPROM
    /// ([`Action::Store`]).
    Stored {
        /// The register.
        register: &'static str,
        /// The value stored.
        value: i32,
        /// The value in the robot file's terms (`wheel`, `1501.5 mA`),
        /// when it has one.
        shown: Option<String>,
        /// Whether the torque was turned off first.
        torque_off: bool,
    },
}

/// What became of one fix.
#[derive(Debug)]
pub struct FixOutcome {
    /// The servo.
    pub id: u8,
    /// What the fix did.
    pub applied: Applied,
    /// `Err` with the reason when it failed.
    pub result: Result<(), FixError>,
}

/// Applies the fix of every fixable finding of the bus `how.bus`, servos at
/// another baud rate first (so the others can reach them), the EEPROM lock
/// last, and the session's homing offsets after every EEPROM write (they
/// are set with the lock closed). A homing offset play would refuse is
/// fixed only by storing it (`how.write_servos`); without that it is left
/// alone. The bus's settings are left as they were.
///
/// Each EEPROM write is one transaction that SIGINT, SIGTERM and SIGHUP
/// cannot cut. When the program caught a stop signal
/// ([`servobus_driver::catch_stop_signals`]), the fixes after the one under
/// way are not applied: their outcomes say [`FixError::Stopped`].
///
/// # Errors
/// Only when the transport fails; a fix that fails is an outcome.
pub fn apply<T: Transport>(
    bus: &mut Bus<T>,
    findings: &[Finding],
    how: &Fixing<'_>,
) -> Result<Vec<FixOutcome>, BusError> {
    let saved = *bus.settings();
    let mut out = Vec::new();
    let mut session_set = false;
    for f in fixes_in_order(findings, how) {
        let Some(action) = f.action else { continue };
        if let Some(signal) = stop_signal() {
            out.push(FixOutcome {
                id: action.id(),
                applied: done(f, how),
                result: Err(FixError::Stopped(signal)),
            });
            continue;
        }
        // Patient, as the examination: a write must not fail on a slow reply.
        bus.set_settings(
            saved
                .with_return_delay(MAX_RETURN_DELAY)
                .with_latency(saved.link.latency + PATIENCE)
                .with_retries(PATIENT_TRIES - 1),
        );
        match run_action(bus, action, how, &mut session_set) {
            Err(FixError::Bus(BusError::Transport(e))) => {
                bus.set_settings(saved);
                return Err(BusError::Transport(e));
            }
            result => out.push(FixOutcome {
                id: action.id(),
                applied: done(f, how),
                result,
            }),
        }
    }
    bus.set_settings(saved);
    Ok(out)
}

/// The findings with a fix to apply, in the order they are applied: baud
/// rates first, the EEPROM lock last, session offsets after every EEPROM
/// write. An offset that can only be stored, and what the robot file asks
/// of a servo's EEPROM, are left out unless `how.write_servos`.
fn fixes_in_order<'f>(findings: &'f [Finding], how: &Fixing<'_>) -> Vec<&'f Finding> {
    let mut todo: Vec<&Finding> = findings
        .iter()
        .filter(|f| match f.action {
            Some(Action::Offset { store_only, .. }) => how.write_servos || !store_only,
            Some(Action::Store { .. }) => how.write_servos,
            other => other.is_some(),
        })
        .collect();
    todo.sort_by_key(|f| match f.action {
        Some(Action::Baud { .. }) => 0,
        Some(Action::Write { register, .. }) if register.name == "lock" => 2,
        Some(Action::Offset { .. }) if !how.write_servos => 3,
        _ => 1,
    });
    todo
}

/// Carries out one fix's `action` on the bus; the session's offsets are set
/// once for the bus (`session_set` says whether they were already).
fn run_action<T: Transport>(
    bus: &mut Bus<T>,
    action: Action,
    how: &Fixing<'_>,
    session_set: &mut bool,
) -> Result<(), FixError> {
    match action {
        Action::Write {
            id,
            register,
            value,
            silent,
            series,
        } => {
            speak_to(bus, silent, series);
            bus.write_register(id, register, value)
                .map(|_| ())
                .map_err(FixError::Bus)
        }
        Action::Store {
            id,
            register,
            value,
            silent,
            series,
            torque_off,
        } => {
            speak_to(bus, silent, series);
            store(bus, id, register, value, torque_off).map_err(FixError::Bus)
        }
        Action::Baud { id, baud, index } => {
            change_baud(bus, id, baud, index).map_err(FixError::Bus)
        }
        Action::Offset {
            id, value, series, ..
        } if how.write_servos => store_offset(bus, id, value, series).map_err(FixError::Bus),
        Action::Offset { .. } => {
            // Play's own routine, once for the bus: it sets every
            // calibrated servo's session offset.
            if *session_set {
                return Ok(());
            }
            *session_set = true;
            session_offsets(bus, how).map_err(|e| match e {
                SessionError::Bus(e) => FixError::Bus(e),
                SessionError::Refused(why) => FixError::Refused(why),
            })
        }
    }
}

/// Sets the bus to speak to a servo of `series` (the register's layout and
/// the lock are its series'), waiting for no reply to a write when
/// `silent`.
fn speak_to<T: Transport>(bus: &mut Bus<T>, silent: bool, series: Series) {
    let mut s = *bus.settings();
    if silent {
        s.replies = StatusLevel::PingAndRead;
    }
    s.series = series;
    bus.set_settings(s);
}

/// Stores `value` in EEPROM `register` of servo `id`
/// (unlock-write-verify-lock), its torque turned off first when
/// `torque_off`. The torque is left off: the run that follows turns it on
/// in the mode it finds.
fn store<T: Transport>(
    bus: &mut Bus<T>,
    id: u8,
    register: &'static Register,
    value: i32,
    torque_off: bool,
) -> Result<(), BusError> {
    if torque_off {
        let torque = bus
            .settings()
            .series
            .map()
            .get("torque_enable")
            .ok_or(BusError::InvalidRequest("no torque_enable on this series"))?;
        bus.write_register(id, torque, 0)?;
        // Read back: the mode changes only once the torque is known off.
        let mut back = [0u8; 1];
        bus.read(id, torque.address, &mut back)?;
        if back[0] != 0 {
            return Err(BusError::Verify {
                id,
                address: torque.address,
                expected: vec![0],
                actual: back.to_vec(),
            });
        }
    }
    bus.write_register(id, register, value).map(|_| ())
}

/// What applying `f`'s fix does, for the report: its fix, or for a homing
/// offset where it goes.
fn done(f: &Finding, how: &Fixing<'_>) -> Applied {
    match f.action {
        Some(Action::Offset { value, .. }) if how.write_servos => Applied::OffsetStored(value),
        Some(Action::Offset { value, .. }) => Applied::OffsetForSession(value),
        Some(Action::Store {
            register,
            value,
            torque_off,
            ..
        }) => Applied::Stored {
            register: register.name,
            value,
            shown: f.setting.as_ref().and_then(|m| m.wanted_as.clone()),
            torque_off,
        },
        _ => Applied::Advice(f.advice.clone()),
    }
}

/// Why the session's offsets could not be set.
enum SessionError {
    /// The bus failed.
    Bus(BusError),
    /// Play's checks refused the robot.
    Refused(Refusal),
}

/// Sets the homing offsets of the bus's calibrated servos for the session,
/// with the routine play runs before it moves.
fn session_offsets<T: Transport>(bus: &mut Bus<T>, how: &Fixing<'_>) -> Result<(), SessionError> {
    prepare_bus(how.robot, how.bus, bus).map_err(|refusal| match refusal {
        Refusal::Bus {
            source: BusError::Transport(e),
            ..
        } => SessionError::Bus(BusError::Transport(e)),
        other => SessionError::Refused(other),
    })
}

/// Stores homing offset `value` in servo `id`'s EEPROM
/// (unlock-write-verify-lock).
fn store_offset<T: Transport>(
    bus: &mut Bus<T>,
    id: u8,
    value: i32,
    series: Series,
) -> Result<(), BusError> {
    let register = series
        .map()
        .get("offset")
        .ok_or(BusError::InvalidRequest("no homing offset on this series"))?;
    let mut s = *bus.settings();
    s.series = series;
    bus.set_settings(s);
    bus.write_register(id, register, value).map(|_| ())
}

/// Moves servo `id`, which listens at `baud`, to the rate of baud-rate
/// index `index`: unlocks it at `baud`, writes the index (the servo may
/// switch before its reply leaves), then reads it back and locks again at
/// the new rate. The transport is left at the new rate.
///
/// # Errors
/// The bus's; [`BusError::Verify`] when the servo does not hold the index
/// at the new rate; [`BusError::InvalidRequest`] for an index outside the
/// baud table.
pub fn change_baud<T: Transport>(
    bus: &mut Bus<T>,
    id: u8,
    baud: u32,
    index: u8,
) -> Result<(), BusError> {
    let home = servobus_protocol::registers::baud_rate(index).ok_or(BusError::InvalidRequest(
        "baud-rate index outside the table",
    ))?;
    let lock = bus.settings().series.map().lock_address;
    // Unlock to lock is one critical section, as every EEPROM write.
    let _hold = servobus_driver::SignalHold::new();
    bus.set_baud(baud)?;
    let unlocked = bus.write(id, lock, &[0]);
    let written = unlocked.and_then(|_| match bus.write(id, addr::BAUD_RATE, &[index]) {
        // The servo may switch before its reply leaves: the read-back at
        // the new rate decides.
        Err(e) if e.is_retryable() => Ok(None),
        other => other,
    });
    bus.set_baud(home)?;
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
        bus.set_baud(baud)?;
        let _ = bus.write(id, lock, &[1]);
        bus.set_baud(home)?;
    }
    verified
}
