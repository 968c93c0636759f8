//! What one serial port serves of a simulated robot: the servos of every
//! bus (or of one named bus) at a single baud rate, as `servobus sim` and
//! Python's `servobus.Sim` serve them on a pseudo-terminal.

use std::collections::HashMap;

use servobus_sim::SimServo;

use super::{SimRobotBuilder, SimRobotError};
use crate::config::Robot;

impl<'a> SimRobotBuilder<'a> {
    /// The robot it simulates.
    pub fn robot(&self) -> &'a Robot {
        self.robot
    }

    /// The servos one port serves, with every option of this builder, and
    /// the baud rate to serve them at: every bus's servos, or those of the
    /// bus named `only`; all at the first served bus's rate (a port has
    /// one).
    ///
    /// # Errors
    /// [`SimRobotError::NoSuchBus`] when no bus is named `only`,
    /// [`SimRobotError::NoBus`] when the robot has none,
    /// [`SimRobotError::SharedId`] when two served joints have the same ID
    /// (one port cannot serve both), and the errors of
    /// [`SimRobotBuilder::servos`].
    pub fn served(&self, only: Option<&str>) -> Result<(u32, Vec<SimServo>), SimRobotError> {
        let robot = self.robot;
        let buses: Vec<_> = match only {
            Some(name) => match robot.buses.iter().find(|b| b.name == name) {
                Some(bus) => vec![bus],
                None => {
                    return Err(SimRobotError::NoSuchBus {
                        file: robot.path.clone(),
                        name: name.to_owned(),
                        buses: robot.buses.iter().map(|b| b.name.clone()).collect(),
                    })
                }
            },
            None => robot.buses.iter().collect(),
        };
        let baud = buses
            .first()
            .map(|b| b.baud)
            .ok_or_else(|| SimRobotError::NoBus {
                file: robot.path.clone(),
            })?;
        let mut seen = HashMap::new();
        let mut servos = Vec::new();
        for bus in buses {
            for joint in &bus.joints {
                if let Some((first_bus, first_joint)) =
                    seen.insert(joint.id, (&bus.name, &joint.name))
                {
                    return Err(SimRobotError::SharedId {
                        file: robot.path.clone(),
                        id: joint.id,
                        joints: Box::new([
                            (first_bus.clone(), first_joint.clone()),
                            (bus.name.clone(), joint.name.clone()),
                        ]),
                    });
                }
            }
            // Every servo listens at the first bus's rate: that is the port's.
            let mut at_rate = bus.clone();
            at_rate.baud = baud;
            servos.extend(self.servos(&at_rate)?);
        }
        Ok((baud, servos))
    }
}
