//! The built-in simulator of a robot file: one simulated servo per joint,
//! at the joint's rest position, with the bus's baud rate and return delay.

use std::path::PathBuf;

use servobus_driver::{Bus, ManualClock};
use servobus_runtime::bus_settings;
use servobus_runtime::config::{BusConfig, JointMap, Robot};
use servobus_sim::{SimBus, SimModel, SimServo};

/// Why a robot file's servos cannot be simulated.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimRobotError {
    /// The bus's baud rate is not one a servo can be set to.
    #[error("{}: bus `{bus}` runs at {baud} baud, which no Feetech servo supports", .file.display())]
    Baud {
        /// The robot file.
        file: PathBuf,
        /// The bus.
        bus: String,
        /// Its baud rate.
        baud: u32,
    },
    /// The simulator has no model of a joint's servo.
    #[error("{}: joint `{joint}`: the simulator has no model {model}", .file.display())]
    Model {
        /// The robot file.
        file: PathBuf,
        /// The joint.
        joint: String,
        /// The model's name.
        model: &'static str,
    },
}

/// The servo baud-table index of `bus`'s baud rate.
///
/// # Errors
/// [`SimRobotError::Baud`] for a rate outside the servo baud table.
pub fn baud_index(robot: &Robot, bus: &BusConfig) -> Result<u8, SimRobotError> {
    (0u8..8)
        .find(|&i| servobus_sim::baud_of_index(i) == Some(bus.baud))
        .ok_or_else(|| SimRobotError::Baud {
            file: robot.path.clone(),
            bus: bus.name.clone(),
            baud: bus.baud,
        })
}

/// The simulated servos of `bus`: each joint's servo with its ID, model, the
/// bus's return delay and baud rate, and its shaft at the joint's rest
/// position.
///
/// # Errors
/// [`SimRobotError`] when a servo cannot be simulated.
pub fn bus_servos(robot: &Robot, bus: &BusConfig) -> Result<Vec<SimServo>, SimRobotError> {
    let baud = baud_index(robot, bus)?;
    let mut servos = Vec::with_capacity(bus.joints.len());
    for joint in &bus.joints {
        let model = SimModel::by_number(joint.model.number)
            .or_else(|| SimModel::by_name(joint.model.name))
            .ok_or_else(|| SimRobotError::Model {
                file: robot.path.clone(),
                joint: joint.name.clone(),
                model: joint.model.name,
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

/// The robot's buses simulated in virtual time, ready for
/// [`servobus_runtime::VirtualRun`]: one [`SimBus`] per robot bus, each with
/// its own [`ManualClock`] (the runtime moves them in step) and the driver
/// settings of the robot file.
///
/// # Errors
/// [`SimRobotError`] when a servo cannot be simulated.
pub fn virtual_buses(robot: &Robot) -> Result<Vec<Bus<SimBus, ManualClock>>, SimRobotError> {
    robot
        .buses
        .iter()
        .map(|bus| {
            let clock = ManualClock::new();
            let sim = SimBus::new(clock.clone(), bus.baud).with_servos(bus_servos(robot, bus)?);
            Ok(Bus::new(sim, clock, bus_settings(bus)))
        })
        .collect()
}
