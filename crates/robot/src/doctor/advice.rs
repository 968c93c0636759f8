//! What to do about a finding, as data: the fix (a bus-tool command with
//! its port, servo and values), the robot file to edit and how, and the
//! steps around them. The command line renders each as it prints it (a
//! fix as the command line that runs it); a program may render them its
//! own way, or serialise them (serde's external tagging: `{"run":
//! {"write": {...}}}`).

use std::path::PathBuf;

use serde::Serialize;

/// The baud rate the bus tools assume when none is given: a [`Fix`] at
/// another rate names its rate.
pub const TOOLS_DEFAULT_BAUD: u32 = 1_000_000;

/// One fix a program (or the command line's bus tools) runs.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Fix {
    /// Write `value` into `register` of servo `id`.
    Write {
        /// The port (`None`: the built-in simulator, a part to fill in).
        port: Option<String>,
        /// The rate the servo answers at.
        baud: u32,
        /// The servo.
        id: u8,
        /// The register's name.
        register: String,
        /// The value.
        value: i32,
    },
    /// Move servo `id`, which answers at `baud`, to the rate of baud-rate
    /// index `index` (a write of its `baud_rate` register).
    SetBaud {
        /// The port.
        port: Option<String>,
        /// The rate the servo answers at now.
        baud: u32,
        /// The servo.
        id: u8,
        /// The baud table's index of the bus's rate.
        index: u8,
    },
    /// Give servo `id` the ID `new_id`.
    SetId {
        /// The port.
        port: Option<String>,
        /// The rate the servo answers at.
        baud: u32,
        /// The servo.
        id: u8,
        /// Its new ID.
        new_id: NewId,
    },
    /// Look for servos on the port at every baud rate.
    ScanAllBauds {
        /// The port.
        port: Option<String>,
    },
    /// Calibrate the robot, writing the calibration to `output`.
    Calibrate {
        /// The robot as a program names it: a built-in's name, else its
        /// file.
        robot: String,
        /// The port.
        port: Option<String>,
        /// The calibration file to write.
        output: String,
    },
    /// Apply every fix of the robot's doctor ([`apply`](super::apply)).
    DoctorFix {
        /// The robot as a program names it.
        robot: String,
        /// The port.
        port: Option<String>,
        /// Store homing offsets in EEPROM instead of setting them for the
        /// session.
        write_servos: bool,
    },
    /// Set an FTDI adapter's latency timer to 1 ms through its sysfs file.
    FtdiLatency {
        /// The timer's sysfs file.
        sysfs: PathBuf,
    },
}

/// The ID a [`Fix::SetId`] gives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NewId {
    /// This ID.
    Id(u8),
    /// A free ID, for the user to choose.
    Free,
    /// The ID of the servo's joint, for the user to look up.
    OfItsJoint,
}

/// A robot file to change.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RobotFile {
    /// A built-in robot (by name): it cannot be edited, only copied first.
    Builtin(String),
    /// The robot file at this path.
    File(PathBuf),
}

/// A change to a robot file.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Change {
    /// Add a joint for the servo with this ID.
    AddJoint {
        /// The servo's ID.
        id: u8,
    },
    /// Name this model for the joint.
    SetModel {
        /// The joint.
        joint: String,
        /// The model found (lower case, as the robot file spells it).
        model: String,
    },
    /// Set the bus's `latency_us` to this (or `auto`).
    SetLatency {
        /// The bus.
        bus: String,
        /// The latency measured, rounded up, in microseconds.
        us: u128,
    },
}

/// A change to make in a robot file.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Edit {
    /// The file.
    pub robot: RobotFile,
    /// The change.
    pub change: Change,
}

/// One of the robot's silent servos that may be answering on another
/// servo's ID ([`Advice::UnplugOthersOneOf`]).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[non_exhaustive]
pub struct SilentServo {
    /// Its ID in the robot file.
    pub id: u8,
    /// Its joint.
    pub joint: String,
    /// The change from the shared ID back to `id`, run with this servo
    /// alone on the bus.
    pub fix: Fix,
}

/// What to do about a finding.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Advice {
    /// Nothing to do.
    #[default]
    None,
    /// Run this fix.
    Run(Fix),
    /// A servo that answers nowhere: check its cable, power and ID, with
    /// this scan.
    CheckCable(Fix),
    /// A servo that answers nowhere while `servo` answers without a joint:
    /// if it is `joint`'s servo, give it its ID with `fix`.
    GiveItsId {
        /// The servo without a joint.
        servo: u8,
        /// The joint whose servo is silent.
        joint: String,
        /// The ID change.
        fix: Fix,
    },
    /// A servo without a joint: give it its joint's ID with `fix`, or add
    /// its joint to the robot file.
    IdOfItsJoint {
        /// The ID change.
        fix: Fix,
        /// The joint to add instead.
        edit: Edit,
    },
    /// Two servos on one ID, one of them `joint`'s: unplug all servos but
    /// that one and run `fix` (it takes hands: no command runs it alone).
    UnplugOthers {
        /// The joint.
        joint: String,
        /// The ID change, with only that servo on the bus.
        fix: Fix,
    },
    /// Two servos on one ID while several of the robot's servos are
    /// silent: one of these most likely has the shared ID, and which one
    /// the bus cannot tell (their replies collide). Each is connected alone
    /// and its fix run: the one on the shared ID takes its own ID back, the
    /// others find no servo on it and nothing changes (it takes hands).
    UnplugOthersOneOf(Vec<SilentServo>),
    /// Two servos on one ID: connect them one at a time and give all but
    /// one a free ID with `fix` (it takes hands).
    OneAtATime(Fix),
    /// The servo is another model: fit `model`, or edit the robot file.
    FitModel {
        /// The model the robot file names.
        model: String,
        /// The change that names the model found instead.
        edit: Edit,
    },
    /// A hot servo: let it cool with the torque off (`fix`).
    Cool(Fix),
    /// A supply out of range: power the bus within `rated` (0.1 V, when the
    /// `model`'s rating is known).
    Supply {
        /// The model (or "servo").
        model: String,
        /// Its rated supply, in 0.1 V: (lowest, highest).
        rated: Option<(u8, u8)>,
    },
    /// A joint outside its limits: turn its torque off (`fix`) and move it
    /// into its limits by hand.
    MoveIntoLimits(Fix),
    /// Update servo `id` to the firmware the others run.
    UpdateFirmware {
        /// The servo.
        id: u8,
        /// The version, major and minor.
        version: (u8, u8),
    },
    /// The supply drops along the chain: shorter, thicker wires, or the
    /// supply fed in at both ends.
    Wiring,
    /// Change the robot file.
    EditRobotFile(Edit),
    /// The servo may have been replaced: if it was, calibrate again.
    CalibrateIfReplaced(Fix),
    /// Nothing to do before play (it sets the offset); `fix` sets it now.
    SetOffsetNow(Fix),
    /// A homing offset rewritten since calibration: `store` the
    /// calibration's, or if the servo or its horn was replaced,
    /// `calibrate` again.
    StoreOrCalibrate {
        /// Storing the calibration's offset.
        store: Fix,
        /// Calibrating again.
        calibrate: Fix,
    },
    /// No calibration: `calibrate`, then have `robot` use it.
    CalibrateFirst {
        /// Calibrating.
        calibrate: Fix,
        /// The robot file to name the calibration in.
        robot: RobotFile,
    },
}

impl Advice {
    /// The one fix that, run alone, does what the advice says (`None` when
    /// it takes hands, an edit, or nothing).
    pub fn command(&self) -> Option<&Fix> {
        match self {
            Advice::Run(fix)
            | Advice::CheckCable(fix)
            | Advice::GiveItsId { fix, .. }
            | Advice::Cool(fix)
            | Advice::MoveIntoLimits(fix)
            | Advice::CalibrateIfReplaced(fix)
            | Advice::SetOffsetNow(fix)
            | Advice::StoreOrCalibrate { store: fix, .. }
            | Advice::CalibrateFirst { calibrate: fix, .. } => Some(fix),
            Advice::None
            | Advice::IdOfItsJoint { .. }
            | Advice::UnplugOthers { .. }
            | Advice::UnplugOthersOneOf(_)
            | Advice::OneAtATime(_)
            | Advice::FitModel { .. }
            | Advice::Supply { .. }
            | Advice::UpdateFirmware { .. }
            | Advice::Wiring
            | Advice::EditRobotFile(_) => None,
        }
    }
}

impl Fix {
    /// Whether the fix has a part for the user to fill in (the port of the
    /// built-in simulator, an ID to choose).
    pub fn has_placeholder(&self) -> bool {
        let port = match self {
            Fix::Write { port, .. }
            | Fix::SetBaud { port, .. }
            | Fix::ScanAllBauds { port }
            | Fix::Calibrate { port, .. }
            | Fix::DoctorFix { port, .. } => port,
            Fix::SetId { port, new_id, .. } => {
                if !matches!(new_id, NewId::Id(_)) {
                    return true;
                }
                port
            }
            Fix::FtdiLatency { .. } => return false,
        };
        port.is_none()
    }
}
