//! The built-in simulator of a robot file: one simulated servo per joint,
//! at the joint's rest position, with the bus's baud rate and return delay.

use anyhow::{bail, Context};
use servobus_runtime::config::{BusConfig, JointMap, Robot};
use servobus_sim::{SimModel, SimServo};

/// The servo baud-table index of `baud`, or an error naming the bus.
pub fn baud_index(robot: &Robot, bus: &BusConfig) -> anyhow::Result<u8> {
    match (0u8..8).find(|&i| servobus_sim::baud_of_index(i) == Some(bus.baud)) {
        Some(index) => Ok(index),
        None => bail!(
            "{}: bus `{}` runs at {} baud, which no Feetech servo supports",
            robot.path.display(),
            bus.name,
            bus.baud
        ),
    }
}

/// The simulated servos of `bus`: each joint's servo with its ID, model, the
/// bus's return delay and baud rate, and its shaft at the joint's rest
/// position.
pub fn bus_servos(robot: &Robot, bus: &BusConfig) -> anyhow::Result<Vec<SimServo>> {
    let baud = baud_index(robot, bus)?;
    let mut servos = Vec::with_capacity(bus.joints.len());
    for joint in &bus.joints {
        let model = SimModel::by_number(joint.model.number)
            .or_else(|| SimModel::by_name(joint.model.name))
            .with_context(|| {
                format!(
                    "{}: joint `{}`: the simulator has no model {}",
                    robot.path.display(),
                    joint.name,
                    joint.model.name
                )
            })?;
        let map = JointMap::new(joint, robot.units);
        let rest = map.to_ticks(robot.units.to_rad(joint.rest()));
        servos.push(
            SimServo::new(model, joint.id)
                .with_return_delay(bus.return_delay)
                .with_byte(servobus_sim::addr::BAUD_RATE, baud)
                .with_position(rest),
        );
    }
    Ok(servos)
}
