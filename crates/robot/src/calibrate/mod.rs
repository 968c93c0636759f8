//! Calibrating a physical robot, and refusing to move one that is not.
//!
//! [`calibrate`] is the procedure `servobus calibrate` runs, driven by a bus
//! and its clock, so that tests in virtual time run the very same code as a
//! person at a terminal:
//!
//! 1. torque off on every servo ([`Step::TorqueOff`]);
//! 2. the person holds the robot in the robot file's calibration pose
//!    ([`Step::HoldPose`]): each joint's tick there is its angle's anchor;
//! 3. the person moves every joint first towards positive angles, then
//!    through its whole range ([`Step::Sweep`]): the first way each joint
//!    goes gives its direction, the extremes its range, unwrapped across
//!    the 4095 -> 0 seam as it is swept;
//! 4. the calibration is returned, to be written to a file.
//!
//! Each step ends when the [`Operator`] confirms (Enter), or, with
//! [`ProcedureOptions::auto`], when the robot has moved and then been held
//! still for [`ProcedureOptions::still_for`].
//!
//! Before a run on real servos, [`prepare_servos`] refuses a robot whose
//! calibration is missing or does not fit the servos found, and puts each
//! servo in the frame its calibration is played in.

use std::path::PathBuf;
use std::time::Duration;

use servobus_driver::BusError;

use crate::config::{BusConfig, JointConfig};

mod lerobot;
mod procedure;
mod servos;
mod store;

pub use lerobot::{from_lerobot, lerobot_value, to_lerobot, LeRobotError, LeRobotMotor, NormMode};
pub use procedure::{calibrate, LiveJoint, ProcedureOptions, MIN_RANGE_DEG};
pub use servos::{
    identify, prepare_bus, prepare_servos, present, torque_off, FoundServo, FAR_OUTSIDE_DEG,
    PATIENCE, PATIENT_RETRIES,
};
pub use store::{store_in_servos, write_frame, write_homing, Store, StoreEnd, StoreError, Stored};

/// A step of the procedure, announced to the [`Operator`] as it begins.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// Torque is now off on every servo: the joints move freely.
    TorqueOff,
    /// Hold the robot in the calibration pose.
    HoldPose,
    /// Move every joint, positive way first, through its whole range.
    Sweep,
    /// The procedure has all it needs.
    Done,
}

/// The person (or script) calibrating: told each step, shown what the
/// procedure sees, and asked whether the step is done.
pub trait Operator {
    /// A step begins.
    fn step(&mut self, step: Step);
    /// The latest readings, one per joint in robot order, at time `at`
    /// (every period while a step lasts).
    fn watch(&mut self, at: Duration, joints: &[LiveJoint]);
    /// Whether the person ended the step (pressed Enter) since last asked.
    fn confirmed(&mut self) -> bool;
}

/// Why a calibration could not be taken.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CalibrateError {
    /// A servo did not answer as it should.
    #[error("joint `{joint}` (servo {id}): {source}")]
    Bus {
        /// The joint.
        joint: String,
        /// Its servo's ID.
        id: u8,
        /// What the bus said.
        #[source]
        source: BusError,
    },
    /// A servo is another model than the robot file says.
    #[error("joint `{joint}`: servo {id} is a {found}, the robot file says {expected}")]
    Model {
        /// The joint.
        joint: String,
        /// Its servo's ID.
        id: u8,
        /// The model found.
        found: &'static str,
        /// The model in the robot file.
        expected: &'static str,
    },
    /// A step did not end.
    #[error("the step did not end within {waited:?} ({})", if *moved { "the robot kept moving" } else { "nothing moved" })]
    Timeout {
        /// How long it waited.
        waited: Duration,
        /// Whether anything moved.
        moved: bool,
    },
    /// A joint was not swept.
    #[error("joint `{joint}` moved only {span_deg:.1} deg: move every joint from one end of its travel to the other")]
    NoRange {
        /// The joint.
        joint: String,
        /// How far it moved.
        span_deg: f64,
    },
    /// A joint turned a whole turn: it has no end stops to calibrate.
    #[error("joint `{joint}` turned a whole turn or more: a joint to calibrate has end stops")]
    FullTurn {
        /// The joint.
        joint: String,
    },
}

impl CalibrateError {
    pub(crate) fn bus(joint: &JointConfig, source: BusError) -> Self {
        CalibrateError::Bus {
            joint: joint.name.clone(),
            id: joint.id,
            source,
        }
    }
}

/// Why a robot may not move on these servos.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Refusal {
    /// The robot file asks for a calibration file that does not exist.
    #[error("the robot file asks for the calibration {} but it does not exist", .path.display())]
    Missing {
        /// The calibration file.
        path: PathBuf,
    },
    /// A servo did not answer.
    #[error("joint `{joint}` (servo {id} on bus `{bus}`): {source}")]
    Bus {
        /// The bus.
        bus: String,
        /// The joint.
        joint: String,
        /// Its servo's ID.
        id: u8,
        /// What the bus said.
        #[source]
        source: BusError,
    },
    /// The servo is another model than the one calibrated.
    #[error(
        "joint `{joint}`: servo {id} is a {found}, the calibration was taken on a {calibrated}"
    )]
    Model {
        /// The joint.
        joint: String,
        /// Its servo's ID.
        id: u8,
        /// The model found.
        found: &'static str,
        /// The model calibrated.
        calibrated: String,
    },
    /// The servo holds another homing offset than the calibration's.
    #[error("joint `{joint}`: servo {id} holds homing offset {found}, the calibration was taken with {calibrated}")]
    Offset {
        /// The joint.
        joint: String,
        /// Its servo's ID.
        id: u8,
        /// The offset found.
        found: i32,
        /// The offset calibrated.
        calibrated: i32,
    },
    /// The servo's EEPROM lock is open: a settings write was cut short
    /// (power loss, a killed program) or another program left it open, so
    /// its settings may be half-written, and any stray write would persist.
    /// The doctor finds what is wrong and `doctor --fix` mends it.
    #[error(
        "joint `{joint}`: servo {id} has its EEPROM lock open: a write of its settings was cut \
         short (power loss, a killed program) or another program left it open, so they may be \
         half-written"
    )]
    Unlocked {
        /// The joint.
        joint: String,
        /// Its servo's ID.
        id: u8,
    },
    /// The joint is far outside its calibrated range.
    #[error("joint `{joint}` (servo {id}) is at {deg:.1} deg, far outside its calibrated range {:.1}..{:.1} deg: is this the robot that was calibrated?", .range.0, .range.1)]
    Position {
        /// The joint.
        joint: String,
        /// Its servo's ID.
        id: u8,
        /// Where it is.
        deg: f64,
        /// The calibrated range, degrees.
        range: (f64, f64),
    },
}

impl Refusal {
    pub(crate) fn bus(config: &BusConfig, joint: &JointConfig, source: BusError) -> Self {
        Refusal::Bus {
            bus: config.name.clone(),
            joint: joint.name.clone(),
            id: joint.id,
            source,
        }
    }
}
