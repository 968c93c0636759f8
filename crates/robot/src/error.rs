//! Why opening, connecting to or playing a robot failed.

use crate::calibrate::Refusal;
use crate::sim::SimRobotError;
use servobus_config::ConfigError;
use servobus_runtime::RunError;

use crate::ports::OpenError;

/// Why a robot could not be opened, connected to, played or checked.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A robot, motion or calibration file is invalid or cannot be read
    /// (the error names the file, line, column and field).
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// A port cannot be opened.
    #[error(transparent)]
    Open(#[from] OpenError),
    /// A bus has no port: neither the target nor the robot file gives one.
    #[error("bus `{bus}` has no port: give one, or name it in the robot file's `port:`")]
    NoPort {
        /// The bus.
        bus: String,
    },
    /// More ports than the robot has buses.
    #[error("{given} ports for a robot of {buses} buses")]
    TooManyPorts {
        /// Ports given.
        given: usize,
        /// Buses of the robot.
        buses: usize,
    },
    /// The robot's servos cannot be simulated.
    #[error(transparent)]
    Simulator(#[from] SimRobotError),
    /// The servos of a bus do not match the robot's calibration: nothing
    /// was read through it and nothing moved.
    #[error("{refusal}")]
    Refused {
        /// The bus.
        bus: String,
        /// Its port.
        port: String,
        /// What does not match.
        #[source]
        refusal: Box<Refusal>,
    },
    /// Storing what the robot file asks of the servos' EEPROM at connect
    /// failed ([`ConnectOptions::write_servos`](crate::ConnectOptions)).
    #[error("bus `{bus}` on {port}: {source}")]
    Store {
        /// The bus.
        bus: String,
        /// Its port.
        port: String,
        /// What failed.
        #[source]
        source: Box<crate::doctor::StoreError>,
    },
    /// The run could not start, a command could not reach it, or a bus
    /// thread failed.
    #[error(transparent)]
    Run(#[from] RunError),
    /// The port of a bus failed in the middle of the doctor's checks.
    #[error("bus `{bus}`: doctor could not finish")]
    Unfinished {
        /// The bus.
        bus: String,
        /// How the port failed.
        #[source]
        source: servobus_driver::BusError,
    },
    /// A starting pose was given for real servos, which start where they
    /// are ([`Robot::connect_at`](crate::Robot::connect_at)).
    #[error("a starting pose sets where the simulator starts; real servos start where they are")]
    PoseOnHardware,
    /// A motion file names its robot by path; a robot given as text has
    /// none, so its motions are planned by the caller
    /// ([`Robot::plan`](crate::Robot::plan) of a motion loaded for a robot
    /// file).
    #[error("the robot `{robot}` was given as text: load its motions with a robot file")]
    NoRobotFile {
        /// The robot's name.
        robot: String,
    },
}
