//! A robot refused because its servos do not match its calibration (or an
//! EEPROM write was left half done), said with the command that mends it.

use std::path::{Path, PathBuf};

use servobus_config::Robot;
use servobus_robot::bus::{Bus, Transport};
use servobus_robot::calibrate::prepare_bus;
use servobus_robot::Refusal;

/// Before any command reads or moves joints through the calibration on real
/// servos: the library's one check ([`prepare_bus`]), with what to run when
/// it refuses.
pub(crate) fn check_bus<T: Transport>(
    robot: &Robot,
    index: usize,
    bus: &mut Bus<T>,
    port: &str,
) -> anyhow::Result<()> {
    prepare_bus(robot, index, bus).map_err(|refusal| refused(robot, &refusal, port))
}

/// [`check_bus`] for every bus.
pub(crate) fn check_buses<T: Transport>(
    robot: &Robot,
    buses: &mut [Bus<T>],
    ports: &[String],
) -> anyhow::Result<()> {
    for (i, (bus, port)) in buses.iter_mut().zip(ports).enumerate() {
        check_bus(robot, i, bus, port)?;
    }
    Ok(())
}

/// The error for `refusal` of `robot` on `port`, with what to run.
pub(crate) fn refused(robot: &Robot, refusal: &Refusal, port: &str) -> anyhow::Error {
    if let Refusal::Unlocked { .. } = refusal {
        return anyhow::anyhow!(
            "{refusal}\nnothing was moved. Find what was left half-written and mend it first:\n  \
             servobus doctor --robot {} --port {port} --fix",
            servobus::builtin::argument(&robot.path)
        );
    }
    let file = robot.calibration.file().map_or_else(
        || PathBuf::from(format!("{}.calibration.yaml", robot.name)),
        Path::to_owned,
    );
    let calibrate = format!(
        "servobus calibrate --robot {} --port {port} -o {}",
        robot.path.display(),
        file.display()
    );
    match refusal {
        // What the user gave names a file that is not there: an input
        // error (exit 2), as play and doctor say it.
        Refusal::Missing { .. } => crate::shared::exit::input(format!(
            "{refusal}\nnothing was moved. Calibrate this robot first:\n  {calibrate}"
        )),
        Refusal::Offset { .. } => anyhow::anyhow!(
            "{refusal}\nnothing was moved. If only the offset was rewritten (by another tool), \
             store the one the calibration plays with:\n  servobus doctor --robot {} --port \
             {port} --fix --write-servos\nif the servo or its horn was replaced, calibrate \
             again:\n  {calibrate}",
            servobus::builtin::argument(&robot.path)
        ),
        _ => anyhow::anyhow!(
            "{refusal}\nnothing was moved. Calibrate this robot first:\n  {calibrate}"
        ),
    }
}
