//! The doctor: checks a bus of servos against the robot file and against
//! the set-up mistakes that break Feetech robots (wrong ID or baud rate,
//! return delays left at the factory 500 us, an EEPROM lock left open,
//! angle limits narrower than the joint's, a gripper free to overheat, an
//! operating mode other than the joint's, ...).
//!
//! Each [`Finding`] names its severity, the servo and register, the value
//! measured, what is wrong and what to do about it ([`Advice`], with the
//! [`Fix`] that repairs it as data). Nothing is written unless the caller
//! asks for it with [`apply`]; EEPROM values are then written with the
//! driver's unlock-write-verify-lock transaction.
//!
//! What the robot file asks of each servo's EEPROM is checked too: the
//! operating mode of its joint (`mode:`; a wheel turns at constant speed,
//! mode 1, a position joint needs mode 0) and the EEPROM registers of its
//! `servo:` settings (`p`, `d`, `i`, `protection_current`,
//! `max_temperature`). A run writes none of them unless asked
//! ([`store_wanted_settings`], `--write-servos` on a run), so a servo that
//! holds other values is a [`Finding`] with a [`SettingMismatch`], fixed only when
//! [`Fixing::write_servos`] asks for EEPROM writes ([`Action::Store`]; the
//! mode with the torque off). The RAM settings (`torque_limit`,
//! `acceleration`) are not checked: a run writes them at every start and
//! the servo forgets them at power-off, so between runs they differ as a
//! rule and the difference says nothing.
//!
//! [`check`] examines every bus of a robot (on its ports, or the built-in
//! simulator) and applies the fixes when asked; [`examine`] and [`apply`]
//! work on one bus a program holds. They are generic over the driver's
//! [`Transport`](servobus_driver::Transport) and
//! [`Clock`](servobus_driver::Clock), so they run on a serial port and on
//! the simulator in virtual time alike.

mod advice;
mod bus_checks;
mod calibration;
mod checks;
mod fix;
mod probe;
mod robot;
mod settings;
mod store;

use serde::Serialize;
use servobus_config::Robot;
use servobus_protocol::registers::{Register, Series};

pub use advice::{Advice, Change, Edit, Fix, NewId, RobotFile, SilentServo, TOOLS_DEFAULT_BAUD};
pub use checks::{rated_voltage_dv, ServoState};
pub use fix::{apply, change_baud, Applied, FixError, FixOutcome};
pub use probe::fix_all_command;
pub use probe::{examine, BusPort, Examined, PortKind};
pub use robot::{check, BusCheck, CheckOptions, Checkup};
pub use settings::SettingMismatch;
pub use store::{store_wanted_settings, StoreError, StoredSetting};

/// How bad a finding is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// Worth knowing; nothing to fix.
    Info,
    /// Works, but badly or riskily.
    Warning,
    /// Breaks motion or the robot.
    Error,
}

impl std::fmt::Display for Severity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Severity::Info => "info",
            Severity::Warning => "warning",
            Severity::Error => "error",
        })
    }
}

/// Where a finding belongs in the set-up of a new robot: the order a new
/// arm needs the advice in (findings are listed in this order).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SetupStep {
    /// Every servo answers, alone, at its ID and the bus's baud rate, and is
    /// the model the robot file names.
    Connect,
    /// The servos' settings: reply delay and level, lock, limits, protection.
    Configure,
    /// The calibration and the homing offsets it plays with.
    Calibrate,
    /// Health and timing: temperature, supply, firmware, pose, latency.
    Check,
}

/// What [`apply`] does about a finding.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Action {
    /// Write `value` into `register` of servo `id` (EEPROM registers with
    /// unlock-write-verify-lock). `silent`: the servo answers no WRITE
    /// (status level 0), so none is waited for.
    Write {
        /// The servo.
        id: u8,
        /// The register.
        register: &'static Register,
        /// The value.
        value: i32,
        /// Whether writes go unanswered.
        silent: bool,
        /// The servo's series (the register's layout and lock).
        series: Series,
    },
    /// Servo `id` listens at `baud`: set its baud-rate register to the
    /// bus's index there, then find it at the bus's rate.
    Baud {
        /// The servo.
        id: u8,
        /// The rate it answers at now.
        baud: u32,
        /// The bus's baud-rate index to write.
        index: u8,
    },
    /// Servo `id`'s homing offset should be `value` (the calibration's play
    /// frame): set for this session as play sets it (lock closed), or,
    /// with [`Fixing::write_servos`], stored in its EEPROM.
    Offset {
        /// The servo.
        id: u8,
        /// The offset the calibration plays with.
        value: i32,
        /// Whether only storing it is a fix: the servo holds neither the
        /// calibration's offset nor the play frame's, so play refuses it
        /// and a session offset would not be accepted.
        store_only: bool,
        /// The servo's series.
        series: Series,
    },
    /// Store `value` in EEPROM `register` of servo `id` because the robot
    /// file asks for it (a joint's operating mode, a `servo:` setting):
    /// only with [`Fixing::write_servos`], with unlock-write-verify-lock.
    Store {
        /// The servo.
        id: u8,
        /// The register.
        register: &'static Register,
        /// The value.
        value: i32,
        /// Whether writes go unanswered.
        silent: bool,
        /// The servo's series.
        series: Series,
        /// Turn the torque off first: a servo switched from position to
        /// wheel mode with its torque on may start turning.
        torque_off: bool,
    },
}

impl Action {
    /// The servo it acts on.
    pub fn id(&self) -> u8 {
        match *self {
            Action::Write { id, .. }
            | Action::Baud { id, .. }
            | Action::Offset { id, .. }
            | Action::Store { id, .. } => id,
        }
    }
}

/// How [`apply`] applies the fixes of one bus.
#[derive(Debug, Clone, Copy)]
pub struct Fixing<'a> {
    /// The robot (its calibration sets the session offsets).
    pub robot: &'a Robot,
    /// The index of the bus in the robot file.
    pub bus: usize,
    /// Store homing offsets in EEPROM instead of setting them for the
    /// session only, and store what the robot file asks of the servos'
    /// EEPROM ([`Action::Store`]; left alone without it).
    pub write_servos: bool,
}

/// One thing found wrong (or worth knowing) about a bus.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Finding {
    /// How bad it is.
    pub severity: Severity,
    /// Where it belongs in setting a robot up.
    pub step: SetupStep,
    /// The robot file's bus.
    pub bus: String,
    /// The servo, when it concerns one.
    pub id: Option<u8>,
    /// The register, when one is at fault.
    pub register: Option<&'static str>,
    /// The value measured, when the finding is about one register's
    /// value (in the register's units).
    pub measured: Option<i32>,
    /// What is wrong.
    pub problem: String,
    /// What to do about it, with the fix as data.
    #[serde(skip)]
    pub advice: Advice,
    /// What [`apply`] does about it, if anything.
    #[serde(skip)]
    pub action: Option<Action>,
    /// The value the robot file asks of the register and the one the
    /// servo holds, when the finding is about a joint's mode or `servo:`
    /// setting. Not serialised with the finding (whose fields readers
    /// take as they are); the command line's JSON adds it.
    #[serde(skip)]
    pub setting: Option<SettingMismatch>,
}

impl Finding {
    /// Whether [`apply`] can apply the fix.
    pub fn fixable(&self) -> bool {
        self.action.is_some()
    }

    /// The flags of `servobus doctor` that apply the fix: `--fix`, or
    /// `--fix --write-servos` where only an EEPROM write fixes it (a
    /// homing offset play refuses, what the robot file asks of the
    /// servo's EEPROM); `None` when [`apply`] cannot fix it.
    pub fn fix_flags(&self) -> Option<&'static str> {
        match self.action? {
            Action::Offset {
                store_only: true, ..
            }
            | Action::Store { .. } => Some("--fix --write-servos"),
            _ => Some("--fix"),
        }
    }

    /// Whether `--fix` alone leaves it alone: its fix is an EEPROM write
    /// that `--write-servos` must ask for.
    pub fn needs_write_servos(&self) -> bool {
        self.fix_flags() == Some("--fix --write-servos")
    }
}

/// The exit status of a set of findings: 0 when nothing is wrong, 1 on
/// warnings only, 2 on errors.
pub fn exit_status(findings: &[Finding]) -> u8 {
    match findings.iter().map(|f| f.severity).max() {
        Some(Severity::Error) => 2,
        Some(Severity::Warning) => 1,
        _ => 0,
    }
}
