//! `servobus doctor` as the command line shows it: the checks are the
//! library's ([`servobus_robot::doctor`]); here each piece of advice is
//! rendered as text, and each fix as the command line that runs it.

pub use servobus_robot::doctor::*;

/// A finding's advice as the command line prints it.
pub trait Shown {
    /// What to do: the command that fixes it, or the steps with the command
    /// among them (empty when there is nothing to do).
    fn fix_text(&self) -> String;
    /// The command that fixes it, exactly as it runs (it appears in
    /// [`fix_text`](Shown::fix_text)); `None` when the fix is done by hand
    /// or the command has a part to fill in (`<PORT>` on the built-in
    /// simulator).
    fn command_line(&self) -> Option<String>;
}

impl Shown for Finding {
    fn fix_text(&self) -> String {
        advice_text(&self.advice)
    }

    fn command_line(&self) -> Option<String> {
        let line = fix_line(self.advice.command()?);
        // A placeholder (`<PORT>`) is for the user to fill in.
        (!line.contains('<')).then_some(line)
    }
}

/// A heading for the findings of `step`: its number in the set-up and what
/// it is about.
pub fn heading(step: SetupStep) -> &'static str {
    match step {
        SetupStep::Connect => {
            "1. connect: every servo answers, alone, at its ID and the bus's rate"
        }
        SetupStep::Configure => "2. configure: the servos' settings",
        SetupStep::Calibrate => "3. calibrate: the calibration and its homing offsets",
        SetupStep::Check => "4. check: health and timing",
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

fn new_id(id: NewId) -> String {
    match id {
        NewId::Id(id) => id.to_string(),
        NewId::Free => "<NEW_ID>".into(),
        NewId::OfItsJoint => "<ID>".into(),
    }
}

/// The command line that runs `fix`.
pub fn fix_line(fix: &Fix) -> String {
    match fix {
        Fix::Write {
            port,
            baud,
            id,
            register,
            value,
        } => format!(
            "servobus write {} --id {id} {register} {value}",
            port_args(port.as_deref(), *baud)
        ),
        Fix::SetBaud {
            port,
            baud,
            id,
            index,
        } => format!(
            "servobus write {} --id {id} baud_rate {index}",
            port_args(port.as_deref(), *baud)
        ),
        Fix::SetId {
            port,
            baud,
            id,
            new_id: to,
        } => format!(
            "servobus set-id {} --id {id} {}",
            port_args(port.as_deref(), *baud),
            new_id(*to)
        ),
        Fix::ScanAllBauds { port } => format!(
            "servobus scan {} --all-bauds",
            port_args(port.as_deref(), TOOLS_DEFAULT_BAUD)
        ),
        // calibrate and doctor take the baud rate from the robot file.
        Fix::Calibrate {
            robot,
            port,
            output,
        } => format!(
            "servobus calibrate --robot {robot} {} -o {output}",
            port_args(port.as_deref(), TOOLS_DEFAULT_BAUD)
        ),
        Fix::DoctorFix {
            robot,
            port,
            write_servos,
        } => format!(
            "servobus doctor --robot {robot} {} --fix{}",
            port_args(port.as_deref(), TOOLS_DEFAULT_BAUD),
            if *write_servos { " --write-servos" } else { "" }
        ),
        Fix::FtdiLatency { sysfs } => format!("echo 1 | sudo tee {}", sysfs.display()),
        // A fix this command line does not know yet.
        _ => format!("{fix:?}"),
    }
}

/// What to do to change the robot file: edit it, or for a built-in robot,
/// write a copy to edit with `servobus init` first.
fn edit_text(edit: &Edit) -> String {
    let change = match &edit.change {
        Change::AddJoint { id } => format!("add a joint with ID {id}"),
        Change::SetModel { joint, model } => format!("set `model: {model}` for joint `{joint}`"),
        Change::SetLatency { bus, us } => {
            format!("set `latency_us: {us}` (or `auto`) on bus `{bus}`")
        }
        _ => format!("{:?}", edit.change),
    };
    match &edit.robot {
        RobotFile::Builtin(name) => format!(
            "the built-in robot cannot be edited: `servobus init --robot {name}` writes \
             robot.yaml; {change} there and pass --robot robot.yaml"
        ),
        RobotFile::File(path) => format!("{change} in {}", path.display()),
    }
}

/// `advice` as the command line prints it.
pub fn advice_text(advice: &Advice) -> String {
    match advice {
        Advice::None => String::new(),
        Advice::Run(fix) => fix_line(fix),
        Advice::EditRobotFile(edit) => edit_text(edit),
        _ => connect_advice(advice)
            .or_else(|| health_advice(advice))
            .or_else(|| calibration_advice(advice))
            .unwrap_or_else(|| format!("{advice:?}")),
    }
}

/// The text of advice on getting every servo to answer at its ID (cables,
/// IDs, servos sharing one); `None` for other advice.
fn connect_advice(advice: &Advice) -> Option<String> {
    Some(match advice {
        Advice::CheckCable(fix) => format!("check its cable, power and ID: {}", fix_line(fix)),
        Advice::GiveItsId { servo, joint, fix } => format!(
            "if servo {servo} is joint `{joint}`'s, give it its ID: {}",
            fix_line(fix)
        ),
        Advice::IdOfItsJoint { fix, edit } => format!(
            "give it the ID of its joint ({}), or {}",
            fix_line(fix),
            edit_text(edit)
        ),
        Advice::UnplugOthers { joint, fix } => format!(
            "unplug every servo but joint `{joint}`'s (one servo on the bus), run `{}`, then \
             plug the others back in",
            fix_line(fix)
        ),
        Advice::UnplugOthersOneOf(silent) => {
            let each: Vec<String> = silent
                .iter()
                .map(|s| format!("joint `{}`'s: `{}`", s.joint, fix_line(&s.fix)))
                .collect();
            format!(
                "connect the silent servos one at a time, each alone on the bus (unplug the \
                 others), and run its command ({}); the one on the shared ID takes its own ID \
                 back, the others find no servo there and nothing changes; then plug the others \
                 back in",
                each.join("; ")
            )
        }
        Advice::OneAtATime(fix) => format!(
            "connect them one at a time and give all but one a free ID: {}",
            fix_line(fix)
        ),
        _ => return None,
    })
}

/// The text of advice on the servos' hardware (model, temperature,
/// supply, limits, firmware, wiring); `None` for other advice.
fn health_advice(advice: &Advice) -> Option<String> {
    Some(match advice {
        Advice::FitModel { model, edit } => format!("fit a {model}, or {}", edit_text(edit)),
        Advice::Cool(fix) => format!("let it cool with the torque off: {}", fix_line(fix)),
        Advice::Supply {
            model,
            rated: Some((lo, hi)),
        } => format!(
            "power the bus from a supply of {:.1}..{:.1} V for the {model}, with wires thick \
             enough that it holds under load",
            f64::from(*lo) / 10.0,
            f64::from(*hi) / 10.0
        ),
        Advice::Supply { rated: None, .. } => "check the supply against the servo's rating".into(),
        Advice::MoveIntoLimits(fix) => format!(
            "turn the torque off ({}) and move the joint into its limits by hand",
            fix_line(fix)
        ),
        Advice::UpdateFirmware {
            id,
            version: (major, minor),
        } => format!("update servo {id} to firmware {major}.{minor} with Feetech's FD software"),
        Advice::Wiring => {
            "use shorter, thicker supply wires, or feed the supply in at both ends of the chain"
                .into()
        }
        _ => return None,
    })
}

/// The text of advice on the calibration and the homing offsets; `None`
/// for other advice.
fn calibration_advice(advice: &Advice) -> Option<String> {
    Some(match advice {
        Advice::CalibrateIfReplaced(fix) => {
            format!("if it was, calibrate again: {}", fix_line(fix))
        }
        Advice::SetOffsetNow(fix) => format!(
            "nothing to do before play; to set it now: {}",
            fix_line(fix)
        ),
        Advice::StoreOrCalibrate { store, calibrate } => format!(
            "if only the offset was rewritten, store the one the calibration plays with in \
             EEPROM: {}; if the \
             servo or its horn was replaced, calibrate again: {}",
            fix_line(store),
            fix_line(calibrate)
        ),
        Advice::CalibrateFirst { calibrate, robot } => {
            format!(
                "{}, {}",
                fix_line(calibrate),
                name_calibration(calibrate, robot)
            )
        }
        _ => return None,
    })
}

/// What an applied fix did, as the report of `--fix` says it: the command
/// it stands for, or for a homing offset or a register the robot file asks
/// for what was set.
pub fn applied_text(applied: &Applied) -> String {
    match applied {
        Applied::OffsetStored(value) => format!("homing offset {value} stored in EEPROM"),
        Applied::OffsetForSession(value) => {
            format!("homing offset {value} set for this session (as play sets it)")
        }
        Applied::Stored {
            register,
            value,
            shown,
            torque_off,
        } => {
            let shown = shown
                .as_ref()
                .map_or_else(String::new, |s| format!(" ({s})"));
            let torque = if *torque_off {
                ", the torque turned off first"
            } else {
                ""
            };
            format!("{register} {value}{shown} stored in EEPROM{torque}")
        }
        Applied::Advice(advice) => advice
            .command()
            .map(fix_line)
            .filter(|line| !line.contains('<'))
            .unwrap_or_else(|| advice_text(advice)),
        _ => format!("{applied:?}"),
    }
}

/// How the robot is told of the calibration `calibrate` writes: uncomment
/// the robot file's `# calibration:` line that names it, add the line, or
/// for a built-in robot pass `--calibration`.
fn name_calibration(calibrate: &Fix, robot: &RobotFile) -> String {
    let output = match calibrate {
        Fix::Calibrate { output, .. } => output.as_str(),
        _ => "calibration.yaml",
    };
    match robot {
        RobotFile::Builtin(_) => {
            format!("then pass --calibration {output} to play, teach and bench")
        }
        RobotFile::File(path) => {
            let text = servobus_config::builtin::file_text(path);
            let commented = text
                .as_deref()
                .and_then(servobus_config::builtin::commented_calibration);
            if commented == Some(output) {
                format!(
                    "then uncomment `calibration: {output}` in {} (or pass --calibration)",
                    path.display()
                )
            } else {
                format!(
                    "then add `calibration: {output}` to {} (or pass --calibration)",
                    path.display()
                )
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_read_as_they_run_with_the_baud_only_when_not_the_default() {
        let write = Fix::Write {
            port: Some("/dev/ttyACM0".into()),
            baud: 115_200,
            id: 3,
            register: "baud_rate".into(),
            value: 0,
        };
        assert_eq!(
            fix_line(&write),
            "servobus write --port /dev/ttyACM0 --baud 115200 --id 3 baud_rate 0"
        );
        let set_id = Fix::SetId {
            port: None,
            baud: 1_000_000,
            id: 1,
            new_id: NewId::Free,
        };
        assert_eq!(
            fix_line(&set_id),
            "servobus set-id --port <PORT> --id 1 <NEW_ID>"
        );
        let fix = Fix::DoctorFix {
            robot: "so101".into(),
            port: Some("/dev/a".into()),
            write_servos: true,
        };
        assert_eq!(
            fix_line(&fix),
            "servobus doctor --robot so101 --port /dev/a --fix --write-servos"
        );
        let baud = Fix::SetBaud {
            port: Some("/dev/a".into()),
            baud: 115_200,
            id: 2,
            index: 0,
        };
        assert_eq!(
            fix_line(&baud),
            "servobus write --port /dev/a --baud 115200 --id 2 baud_rate 0"
        );
    }
}
