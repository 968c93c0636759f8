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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{load_robot, RobotOptions};
    use crate::sim::SimRobot;

    /// The built-in two-bus hexapod: bus `left` IDs 1..=9, `right` 10..=18,
    /// both at 1 Mbps.
    fn hexapod() -> Robot {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/robots");
        load_robot(&dir.join("hexapod-2bus.yaml"), &RobotOptions::default())
            .expect("the built-in hexapod loads")
    }

    fn ids(servos: &[SimServo]) -> Vec<u8> {
        servos.iter().map(SimServo::id).collect()
    }

    #[test]
    fn every_bus_or_the_named_one_is_served_at_one_rate() {
        let robot = hexapod();
        let builder = SimRobot::builder(&robot);
        let (baud, all) = builder.served(None).expect("both buses");
        assert_eq!(baud, 1_000_000);
        assert_eq!(ids(&all), (1..=18).collect::<Vec<u8>>());
        let (_, right) = builder.served(Some("right")).expect("one bus");
        assert_eq!(ids(&right), (10..=18).collect::<Vec<u8>>());
    }

    #[test]
    fn an_unknown_bus_and_an_id_on_two_buses_are_refused() {
        let mut robot = hexapod();
        match SimRobot::builder(&robot).served(Some("middle")) {
            Err(SimRobotError::NoSuchBus { name, buses, .. }) => {
                assert_eq!(name, "middle");
                assert_eq!(buses, ["left", "right"]);
            }
            other => panic!("expected NoSuchBus, got {other:?}"),
        }
        robot.buses[1].joints[0].id = 1;
        let err = SimRobot::builder(&robot)
            .served(None)
            .expect_err("ID 1 twice");
        assert!(
            matches!(err, SimRobotError::SharedId { id: 1, .. }),
            "{err:?}"
        );
        let text = err.to_string();
        assert!(
            text.contains("on bus `left`") && text.contains("on bus `right`"),
            "{text}"
        );
        // One bus alone is served: the other's ID does not matter.
        assert!(SimRobot::builder(&robot).served(Some("right")).is_ok());
    }
}
