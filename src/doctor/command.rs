//! The command lines that fix findings, as data: which command, on which
//! port and servo, with which values. A finding shows one as the command
//! exactly as it runs ([`std::fmt::Display`]).

use std::fmt;
use std::path::PathBuf;

/// The baud rate the bus tools assume without `--baud`.
pub(crate) const TOOLS_DEFAULT_BAUD: u32 = 1_000_000;

/// A command line that fixes a finding.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum FixCommand {
    /// `servobus write`: `value` into `register` of servo `id`.
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
    /// `servobus set-id`: servo `id` to `new_id`.
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
    /// `servobus scan --all-bauds` of the port.
    ScanAllBauds {
        /// The port.
        port: Option<String>,
    },
    /// `servobus calibrate` of the robot, writing the calibration to
    /// `output`.
    Calibrate {
        /// The robot as the command line names it.
        robot: String,
        /// The port.
        port: Option<String>,
        /// The calibration file to write.
        output: String,
    },
    /// `servobus doctor --fix` of the robot.
    DoctorFix {
        /// The robot as the command line names it.
        robot: String,
        /// The port.
        port: Option<String>,
        /// Store homing offsets in EEPROM (`--write-servos`).
        write_servos: bool,
    },
    /// Setting an FTDI adapter's latency timer to 1 ms through its sysfs
    /// file.
    FtdiLatency {
        /// The timer's sysfs file.
        sysfs: PathBuf,
    },
}

/// The ID a `servobus set-id` gives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NewId {
    /// This ID.
    Id(u8),
    /// A free ID, for the user to choose (`<NEW_ID>`).
    Free,
    /// The ID of the servo's joint, for the user to look up (`<ID>`).
    OfItsJoint,
}

impl fmt::Display for NewId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NewId::Id(id) => write!(f, "{id}"),
            NewId::Free => f.write_str("<NEW_ID>"),
            NewId::OfItsJoint => f.write_str("<ID>"),
        }
    }
}

/// `--port PORT`, with `--baud` when `baud` is not the bus tools' default.
fn port_args(port: Option<&str>, baud: u32) -> String {
    let port = port.unwrap_or("<PORT>");
    if baud == TOOLS_DEFAULT_BAUD {
        format!("--port {port}")
    } else {
        format!("--port {port} --baud {baud}")
    }
}

impl fmt::Display for FixCommand {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FixCommand::Write {
                port,
                baud,
                id,
                register,
                value,
            } => write!(
                f,
                "servobus write {} --id {id} {register} {value}",
                port_args(port.as_deref(), *baud)
            ),
            FixCommand::SetId {
                port,
                baud,
                id,
                new_id,
            } => write!(
                f,
                "servobus set-id {} --id {id} {new_id}",
                port_args(port.as_deref(), *baud)
            ),
            FixCommand::ScanAllBauds { port } => write!(
                f,
                "servobus scan {} --all-bauds",
                port_args(port.as_deref(), TOOLS_DEFAULT_BAUD)
            ),
            // calibrate and doctor take the baud rate from the robot file.
            FixCommand::Calibrate {
                robot,
                port,
                output,
            } => write!(
                f,
                "servobus calibrate --robot {robot} {} -o {output}",
                port_args(port.as_deref(), TOOLS_DEFAULT_BAUD)
            ),
            FixCommand::DoctorFix {
                robot,
                port,
                write_servos,
            } => write!(
                f,
                "servobus doctor --robot {robot} {} --fix{}",
                port_args(port.as_deref(), TOOLS_DEFAULT_BAUD),
                if *write_servos { " --write-servos" } else { "" }
            ),
            FixCommand::FtdiLatency { sysfs } => {
                write!(f, "echo 1 | sudo tee {}", sysfs.display())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_read_as_they_run_with_the_baud_only_when_not_the_default() {
        let write = FixCommand::Write {
            port: Some("/dev/ttyACM0".into()),
            baud: 115_200,
            id: 3,
            register: "baud_rate".into(),
            value: 0,
        };
        assert_eq!(
            write.to_string(),
            "servobus write --port /dev/ttyACM0 --baud 115200 --id 3 baud_rate 0"
        );
        let set_id = FixCommand::SetId {
            port: None,
            baud: 1_000_000,
            id: 1,
            new_id: NewId::Free,
        };
        assert_eq!(
            set_id.to_string(),
            "servobus set-id --port <PORT> --id 1 <NEW_ID>"
        );
        let fix = FixCommand::DoctorFix {
            robot: "so101".into(),
            port: Some("/dev/a".into()),
            write_servos: true,
        };
        assert_eq!(
            fix.to_string(),
            "servobus doctor --robot so101 --port /dev/a --fix --write-servos"
        );
    }
}
