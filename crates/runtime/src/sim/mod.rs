//! The built-in simulator of a robot file: one simulated servo per joint,
//! with the bus's baud rate and return delay, its shaft at the joint's rest
//! position (or a pose you give).
//!
//! This is the one place where a robot file becomes simulated servos: the
//! command line (`servobus sim`, `play` and `bench` without `--port`), the
//! examples and the tests all build their simulator here.
//!
//! ```
//! use servobus_runtime::config::load_robot;
//! use servobus_runtime::sim::SimRobot;
//!
//! # let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/robots");
//! let robot = load_robot(&dir.join("so101.yaml"))?;
//! let sim = SimRobot::builder(&robot).build()?;
//! // One driver bus per robot bus, in virtual time, ready for `VirtualRun`.
//! let buses = sim.driver_buses();
//! assert_eq!(buses.len(), robot.buses.len());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::PathBuf;

use crate::bus_settings;
use crate::config::{BusConfig, JointMap, Robot};
use servobus_driver::{Bus, ManualClock};
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
    /// A start pose does not have one angle per joint.
    #[error("{}: a start pose of {got} angles for a robot of {want} joints", .file.display())]
    Pose {
        /// The robot file.
        file: PathBuf,
        /// Angles given.
        got: usize,
        /// Joints of the robot.
        want: usize,
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
    let rest: Vec<f64> = bus.joints.iter().map(|j| j.rest()).collect();
    servos_at(robot, bus, &rest)
}

/// The servos of `bus` with their shafts at `pose` (robot units, one angle
/// per joint of the bus, in the bus's joint order): a simulated robot that
/// starts away from its rest position, e.g. on a pty.
///
/// # Errors
/// [`SimRobotError`] when a servo cannot be simulated.
pub fn servos_at(
    robot: &Robot,
    bus: &BusConfig,
    pose: &[f64],
) -> Result<Vec<SimServo>, SimRobotError> {
    let baud = baud_index(robot, bus)?;
    let mut servos = Vec::with_capacity(bus.joints.len());
    for (joint, &angle) in bus.joints.iter().zip(pose) {
        let model = SimModel::by_number(joint.model.number)
            .or_else(|| SimModel::by_name(joint.model.name))
            .ok_or_else(|| SimRobotError::Model {
                file: robot.path.clone(),
                joint: joint.name.clone(),
                model: joint.model.name,
            })?;
        let map = JointMap::new(joint, robot.units);
        let ticks = map.to_ticks(robot.units.to_rad(angle));
        servos.push(
            SimServo::new(model, joint.id)
                .with_return_delay(bus.return_delay)
                .with_byte(servobus_sim::addr::BAUD_RATE, baud)
                .with_position(ticks),
        );
    }
    Ok(servos)
}

/// The robot's buses simulated in virtual time, ready for
/// [`crate::VirtualRun`]: one [`SimBus`] per robot bus, each with its own
/// [`ManualClock`] (the runtime moves them in step) and the driver settings
/// of the robot file. Shorthand for `SimRobot::builder(robot).build()?.driver_buses()`.
///
/// # Errors
/// [`SimRobotError`] when a servo cannot be simulated.
pub fn virtual_buses(robot: &Robot) -> Result<Vec<Bus<SimBus, ManualClock>>, SimRobotError> {
    Ok(SimRobot::builder(robot).build()?.driver_buses())
}

/// A robot file's servos on simulated buses in virtual time.
///
/// Build one with [`SimRobot::builder`]. The [`SimBus`] handles it holds
/// share their servos with every driver bus made from them, so a test can
/// run the robot through [`SimRobot::driver_buses`] and inspect the servos
/// through [`SimRobot::buses`].
#[derive(Debug, Clone)]
pub struct SimRobot {
    buses: Vec<SimBus>,
    settings: Vec<servobus_driver::BusSettings>,
}

/// Options of a [`SimRobot`]; see [`SimRobot::builder`].
#[derive(Debug, Clone)]
pub struct SimRobotBuilder<'a> {
    robot: &'a Robot,
    pose: Option<Vec<f64>>,
}

impl SimRobot {
    /// The options of a simulated `robot`: by default every shaft at its
    /// joint's rest position.
    pub fn builder(robot: &Robot) -> SimRobotBuilder<'_> {
        SimRobotBuilder { robot, pose: None }
    }

    /// The simulated buses, one per robot bus, in the robot file's order.
    pub fn buses(&self) -> &[SimBus] {
        &self.buses
    }

    /// Driver buses on the simulated buses (each on its bus's own clock,
    /// with the robot file's settings), ready for [`crate::VirtualRun`].
    pub fn driver_buses(&self) -> Vec<Bus<SimBus, ManualClock>> {
        self.buses
            .iter()
            .zip(&self.settings)
            .map(|(sim, settings)| Bus::new(sim.clone(), sim.clock().clone(), *settings))
            .collect()
    }
}

impl SimRobotBuilder<'_> {
    /// Every shaft at `pose` instead of the rest positions: one angle per
    /// joint in the robot's joint order, in the robot file's units.
    #[must_use]
    pub fn pose(mut self, pose: &[f64]) -> Self {
        self.pose = Some(pose.to_vec());
        self
    }

    /// The simulated robot.
    ///
    /// # Errors
    /// [`SimRobotError`] when a servo cannot be simulated or the pose does
    /// not fit the robot.
    pub fn build(self) -> Result<SimRobot, SimRobotError> {
        let robot = self.robot;
        let pose = match self.pose {
            Some(p) if p.len() != robot.joint_count() => {
                return Err(SimRobotError::Pose {
                    file: robot.path.clone(),
                    got: p.len(),
                    want: robot.joint_count(),
                })
            }
            Some(p) => p,
            None => robot.joints().map(|j| j.rest()).collect(),
        };
        let mut buses = Vec::with_capacity(robot.buses.len());
        let mut settings = Vec::with_capacity(robot.buses.len());
        let mut first = 0;
        for bus in &robot.buses {
            let n = bus.joints.len();
            let servos = servos_at(robot, bus, &pose[first..first + n])?;
            first += n;
            buses.push(SimBus::new(ManualClock::new(), bus.baud).with_servos(servos));
            settings.push(bus_settings(bus));
        }
        Ok(SimRobot { buses, settings })
    }
}
