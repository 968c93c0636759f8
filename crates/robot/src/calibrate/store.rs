//! Storing a calibration in the servos' EEPROM (`calibrate --write-servos`):
//! each servo's homing offset and position limits as one transaction.
//!
//! A servo is written whole or left as it was: its three registers go in
//! one [`Bus::write_eeprom_all`], which holds SIGINT, SIGTERM and SIGHUP
//! until the servo is locked again and puts back what it wrote when a step
//! fails. Between two servos, a stop signal the program catches
//! ([`servobus_driver::catch_stop_signals`]) ends the store there: what was
//! written is returned ([`Stored`]), with the calibration in the frames the
//! servos now hold, so that it can still be saved.

use servobus_driver::{stop_signal, Bus, BusError, StopSignal, Transport};

use crate::config::seam::{centring_offset, turn_ticks};
use crate::config::{Calibration, JointCalibration, JointConfig, PlayFrame, Robot};

use super::servos::register;

/// What [`store_in_servos`] writes to each servo's EEPROM.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Store {
    /// The homing offset that centres the measured range on the turn
    /// ([`write_homing`]): after a calibration measured here.
    Centred,
    /// The joint's play frame ([`write_frame`] of
    /// [`JointCalibration::play_frame`]), as LeRobot stores an imported
    /// calibration.
    PlayFrame,
}

/// A servo whose EEPROM could not be written. Its registers were put back
/// as they were (unless the bus failed while putting them back).
#[derive(Debug, thiserror::Error)]
#[error("joint `{joint}` (servo {id}): writing the EEPROM")]
pub struct StoreError {
    /// The joint.
    pub joint: String,
    /// Its servo's ID.
    pub id: u8,
    /// The failed step's bus error.
    #[source]
    pub source: BusError,
}

/// Why [`store_in_servos`] ended before the last servo.
#[derive(Debug)]
#[non_exhaustive]
pub enum StoreEnd {
    /// A stop signal came: the servo being written was finished first.
    Stopped(StopSignal),
    /// A servo could not be written (it was left as it was).
    Failed(StoreError),
}

/// What [`store_in_servos`] did.
#[derive(Debug)]
pub struct Stored {
    /// The calibration, each joint in the frame its servo now holds: the
    /// new one for the joints written, the one measured for the others.
    pub calibration: Calibration,
    /// The joints written (unlocked, written, verified, locked), in order.
    pub written: Vec<String>,
    /// The joints not written, in order.
    pub not_written: Vec<String>,
    /// Why it ended before the last joint; `None` when every joint is
    /// written.
    pub ended: Option<StoreEnd>,
}

/// Stores `cal` in the EEPROM of every servo of `robot` on `buses` (one
/// per robot bus, in order) as `how` says, joint by joint in the robot's
/// joint order, each as one transaction. `written` is told each joint and
/// its calibration once it is stored (unlocked, written, verified, locked).
///
/// It ends early, between two servos, when a servo cannot be written (left
/// as it was) or when the program caught a stop signal
/// ([`servobus_driver::catch_stop_signals`]); [`Stored`] says which joints
/// were written and holds the calibration in the frames the servos hold.
pub fn store_in_servos<T: Transport>(
    robot: &Robot,
    buses: &mut [Bus<T>],
    mut cal: Calibration,
    how: Store,
    mut written: impl FnMut(&JointConfig, &JointCalibration),
) -> Stored {
    let mut done = Vec::new();
    let mut ended = None;
    let mut stored = cal.joints.iter_mut();
    'buses: for (bus, config) in buses.iter_mut().zip(&robot.buses) {
        for joint in &config.joints {
            let Some(jc) = stored.next() else {
                break 'buses;
            };
            if let Some(signal) = stop_signal() {
                ended = Some(StoreEnd::Stopped(signal));
                break 'buses;
            }
            let result = match how {
                Store::Centred => write_homing(bus, joint, jc),
                Store::PlayFrame => write_frame(bus, joint, jc, jc.play_frame()),
            };
            match result {
                Ok(new) => {
                    *jc = new;
                    written(joint, jc);
                    done.push(joint.name.clone());
                }
                Err(source) => {
                    ended = Some(StoreEnd::Failed(StoreError {
                        joint: joint.name.clone(),
                        id: joint.id,
                        source,
                    }));
                    break 'buses;
                }
            }
        }
    }
    let not_written = robot
        .joints()
        .take(cal.joints.len())
        .map(|j| j.name.clone())
        .filter(|name| !done.contains(name))
        .collect();
    Stored {
        calibration: cal,
        written: done,
        not_written,
        ended,
    }
}

/// Writes to `joint`'s servo's EEPROM (one transaction: unlock, write,
/// verify, lock) the homing offset that centres its measured range on the
/// turn, and position limits at that range, and returns the calibration in
/// the new frame. A model without the offset register keeps its
/// calibration.
///
/// # Errors
/// The failed step's bus error (the servo is then as it was).
pub fn write_homing<T: Transport>(
    bus: &mut Bus<T>,
    joint: &JointConfig,
    cal: &JointCalibration,
) -> Result<JointCalibration, BusError> {
    let Some(turn) = turn_ticks(joint.model) else {
        return Ok(cal.clone());
    };
    let (homing_offset, shift) = centring_offset(cal.range, cal.homing_offset, turn);
    write_frame(
        bus,
        joint,
        cal,
        PlayFrame {
            homing_offset,
            shift,
        },
    )
}

/// Writes to `joint`'s servo's EEPROM the homing offset of `frame` and
/// position limits at the calibrated range in that frame (what LeRobot
/// checks to call a servo calibrated), as one transaction; returns the
/// calibration in `frame`. A model without the offset register keeps its
/// calibration.
///
/// # Errors
/// The failed step's bus error (the servo is then as it was);
/// [`BusError::InvalidRequest`] when the range does not fit the position
/// registers in that frame (nothing is written).
pub fn write_frame<T: Transport>(
    bus: &mut Bus<T>,
    joint: &JointConfig,
    cal: &JointCalibration,
    frame: PlayFrame,
) -> Result<JointCalibration, BusError> {
    let Some(offset_reg) = joint.model.map().get("offset") else {
        return Ok(cal.clone());
    };
    if turn_ticks(joint.model).is_none() {
        return Ok(cal.clone());
    }
    let moved = cal.in_frame(frame);
    let limit = |v: i64| {
        i32::try_from(v)
            .ok()
            .filter(|v| (0..=joint.model.max_position() as i32).contains(v))
            .ok_or(BusError::InvalidRequest(
                "range outside the position registers",
            ))
    };
    let (lo, hi) = (limit(moved.range[0])?, limit(moved.range[1])?);
    let regs = [
        (offset_reg, frame.homing_offset),
        (register(joint.model, "min_angle_limit")?, lo),
        (register(joint.model, "max_angle_limit")?, hi),
    ];
    let order = bus.settings().series.byte_order();
    let mut bytes = [[0u8; 4]; 3];
    for ((reg, value), out) in regs.iter().zip(&mut bytes) {
        let out = out
            .get_mut(..usize::from(reg.size))
            .ok_or(BusError::InvalidRequest("register wider than 4 bytes"))?;
        reg.encode(*value, order, out).map_err(BusError::Value)?;
    }
    let changes: [(u8, &[u8]); 3] = [
        (regs[0].0.address, &bytes[0][..usize::from(regs[0].0.size)]),
        (regs[1].0.address, &bytes[1][..usize::from(regs[1].0.size)]),
        (regs[2].0.address, &bytes[2][..usize::from(regs[2].0.size)]),
    ];
    bus.write_eeprom_all(joint.id, &changes)?;
    Ok(moved)
}
