//! What calibrating and playing ask of the servos themselves: who is there,
//! torque off, Homing_Offset set for the session (stored in EEPROM by
//! [`store_in_servos`](super::store_in_servos) with `--write-servos`), and
//! the check that refuses to move a robot whose servos are not the ones its
//! calibration was taken on.

use std::time::Duration;

use servobus_driver::{Bus, BusError, Transport};
use servobus_protocol::registers::{addr, model_by_number, Model, Register};

use crate::config::seam::turn_ticks;
use crate::config::{BusConfig, JointCalibration, JointConfig, JointMap, Robot, RobotCalibration};

use super::{CalibrateError, Refusal};

/// How far outside its calibrated range a joint may be found before a run
/// refuses to start, degrees: beyond this the servo is not where the
/// calibration says (a horn refitted, a servo swapped), or the joint is
/// pressed past a stop.
pub const FAR_OUTSIDE_DEG: f64 = 15.0;

/// Reply deadline allowance of every step that is not timed (calibrating,
/// and the calibration check every command runs before its first read): a
/// slow adapter or a loaded host (a pty served by a process that waits for
/// the CPU) must not make a present servo look absent. A servo that is
/// really missing costs this much per try, once.
pub const PATIENCE: Duration = Duration::from_millis(50);

/// Tries per transaction of the untimed steps: a reply lost now and then
/// must not end a calibration or refuse a run.
pub const PATIENT_RETRIES: u8 = 3;

/// One servo as found on the bus.
#[derive(Debug, Clone, PartialEq)]
pub struct FoundServo {
    /// Its model, from register 3.
    pub model: &'static Model,
    /// Firmware version, `major.minor`.
    pub firmware: String,
    /// Its homing offset (0 for models without the register).
    pub homing_offset: i32,
}

/// The register `name` of `model`'s control table.
pub(crate) fn register(model: &Model, name: &'static str) -> Result<&'static Register, BusError> {
    model.map().get(name).ok_or(BusError::InvalidRequest(
        "register missing from the model's table",
    ))
}

/// Reads `joint`'s servo: model, firmware and homing offset.
///
/// # Errors
/// The bus error of the first read that failed; [`BusError::UnknownModel`]
/// for a model number servobus does not know.
pub fn identify<T: Transport>(
    bus: &mut Bus<T>,
    joint: &JointConfig,
) -> Result<FoundServo, BusError> {
    let (number, _) = bus.read_register(joint.id, register(joint.model, "model_number")?)?;
    // A two-byte unsigned register: it always fits.
    let number = u16::try_from(number).unwrap_or(u16::MAX);
    let model = model_by_number(number).ok_or(BusError::UnknownModel {
        id: joint.id,
        number,
    })?;
    let mut fw = [0u8; 2];
    bus.read(joint.id, addr::FIRMWARE_MAJOR, &mut fw)?;
    let homing_offset = match model.map().get("offset") {
        Some(reg) if turn_ticks(model).is_some() => bus.read_register(joint.id, reg)?.0,
        _ => 0,
    };
    Ok(FoundServo {
        model,
        firmware: format!("{}.{}", fw[0], fw[1]),
        homing_offset,
    })
}

/// Present position of `joint`'s servo.
///
/// # Errors
/// The read's bus error.
pub fn present<T: Transport>(bus: &mut Bus<T>, joint: &JointConfig) -> Result<i32, BusError> {
    Ok(bus
        .read_register(joint.id, register(joint.model, "present_position")?)?
        .0)
}

/// Torque off on every servo of `bus`.
///
/// # Errors
/// The first servo whose write failed.
pub fn torque_off<T: Transport>(
    bus: &mut Bus<T>,
    config: &BusConfig,
) -> Result<(), CalibrateError> {
    for joint in &config.joints {
        bus.write(joint.id, addr::TORQUE_ENABLE, &[0])
            .map_err(|e| CalibrateError::bus(joint, e))?;
    }
    Ok(())
}

/// Makes the servos match the robot's calibration: the one routine every
/// command runs on real servos before its first reading of a joint through
/// the calibration (play, bench, teach, monitor, doctor, stream, follow).
///
/// It refuses a servo whose EEPROM lock is open ([`Refusal::Unlocked`]:
/// a settings write was cut short, or another program left it open), and
/// a robot whose calibration is missing or does not match the servos
/// found, and puts every calibrated servo in its play frame. After a
/// power-up a servo holds the homing offset of its EEPROM; a range that
/// crosses the seam is played in a frame whose homing offset centres it,
/// and unless `--write-servos` stored that offset, it is written here with
/// the lock closed, which applies it until the servo is switched off and
/// leaves its EEPROM as it was. Without this, the same joint reads a
/// different angle after every power cycle. Nothing moves here: torque is
/// not touched.
///
/// The check is not timed: it runs with patient deadlines ([`PATIENCE`],
/// [`PATIENT_RETRIES`]) and gives each bus its own settings back after.
///
/// # Errors
/// A [`Refusal`] naming the joint and what is wrong.
pub fn prepare_servos<T: Transport>(robot: &Robot, buses: &mut [Bus<T>]) -> Result<(), Refusal> {
    if let RobotCalibration::Missing(path) = &robot.calibration {
        return Err(Refusal::Missing { path: path.clone() });
    }
    for (index, bus) in buses.iter_mut().enumerate() {
        prepare_bus(robot, index, bus)?;
    }
    Ok(())
}

/// [`prepare_servos`] for the robot's bus `index` alone, on `bus`.
///
/// # Errors
/// As [`prepare_servos`].
pub fn prepare_bus<T: Transport>(
    robot: &Robot,
    index: usize,
    bus: &mut Bus<T>,
) -> Result<(), Refusal> {
    if let RobotCalibration::Missing(path) = &robot.calibration {
        return Err(Refusal::Missing { path: path.clone() });
    }
    let Some(config) = robot.buses.get(index) else {
        return Ok(());
    };
    // At the bus's own deadlines: a servo missing costs no patience here.
    for joint in &config.joints {
        refuse_unlocked(bus, joint)?;
    }
    if config.joints.iter().all(|j| j.calibration.is_none()) {
        return Ok(());
    }
    let saved = *bus.settings();
    bus.set_settings(
        saved
            .with_latency(saved.link.latency.max(PATIENCE))
            .with_retries(PATIENT_RETRIES),
    );
    let checked = config
        .joints
        .iter()
        .try_for_each(|joint| match &joint.calibration {
            Some(cal) => prepare_joint(bus, config, joint, cal, robot),
            None => Ok(()),
        });
    bus.set_settings(saved);
    checked
}

/// Refuses a servo whose EEPROM lock is open (see [`Refusal::Unlocked`]).
/// A servo that does not answer (or whose reply is lost) is not refused
/// here: the checks after this one, or the run, say it is missing in their
/// own way.
fn refuse_unlocked<T: Transport>(bus: &mut Bus<T>, joint: &JointConfig) -> Result<(), Refusal> {
    let mut lock = [1u8];
    match bus.read(joint.id, joint.model.map().lock_address, &mut lock) {
        Ok(_) if lock[0] == 0 => Err(Refusal::Unlocked {
            joint: joint.name.clone(),
            id: joint.id,
        }),
        _ => Ok(()),
    }
}

fn prepare_joint<T: Transport>(
    bus: &mut Bus<T>,
    config: &BusConfig,
    joint: &JointConfig,
    cal: &JointCalibration,
    robot: &Robot,
) -> Result<(), Refusal> {
    let found = identify(bus, joint).map_err(|e| Refusal::bus(config, joint, e))?;
    if !found.model.name.eq_ignore_ascii_case(&cal.model) {
        return Err(Refusal::Model {
            joint: joint.name.clone(),
            id: joint.id,
            found: found.model.name,
            calibrated: cal.model.clone(),
        });
    }
    let frame = cal.play_frame();
    if found.homing_offset != frame.homing_offset {
        if found.homing_offset != cal.homing_offset {
            return Err(Refusal::Offset {
                joint: joint.name.clone(),
                id: joint.id,
                found: found.homing_offset,
                calibrated: cal.homing_offset,
            });
        }
        session_offset(bus, joint, frame.homing_offset)
            .map_err(|e| Refusal::bus(config, joint, e))?;
    }
    let tick = present(bus, joint).map_err(|e| Refusal::bus(config, joint, e))?;
    let map = JointMap::new(joint, robot.units);
    let deg = map.from_ticks(tick).to_degrees();
    let c = cal.in_frame(frame);
    let (a, b) = (
        c.degrees_at(joint.model, c.range[0] as f64),
        c.degrees_at(joint.model, c.range[1] as f64),
    );
    let (lo, hi) = (a.min(b), a.max(b));
    if deg < lo - FAR_OUTSIDE_DEG || deg > hi + FAR_OUTSIDE_DEG {
        return Err(Refusal::Position {
            joint: joint.name.clone(),
            id: joint.id,
            deg,
            range: (lo, hi),
        });
    }
    Ok(())
}

/// Writes a homing offset that lasts until the servo is switched off: the
/// lock is closed first (a write with it open would persist), then the
/// offset is written and read back.
fn session_offset<T: Transport>(
    bus: &mut Bus<T>,
    joint: &JointConfig,
    offset: i32,
) -> Result<(), BusError> {
    let reg = register(joint.model, "offset")?;
    let lock = joint.model.map().lock_address;
    bus.write(joint.id, lock, &[1])?;
    let mut bytes = [0u8; 2];
    reg.encode(offset, joint.model.series.byte_order(), &mut bytes)
        .map_err(BusError::Value)?;
    bus.write(joint.id, reg.address, &bytes)?;
    let (back, _) = bus.read_register(joint.id, reg)?;
    if back != offset {
        return Err(BusError::Verify {
            id: joint.id,
            address: reg.address,
            expected: bytes.to_vec(),
            actual: Vec::new(),
        });
    }
    Ok(())
}
