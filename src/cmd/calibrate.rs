//! `servobus calibrate`: where one physical robot's joints really are.
//!
//! Runs the procedure of [`servobus_robot::calibrate`] on the robot's
//! servos (torque off, the calibration pose held, every joint swept) and
//! writes the calibration file; or imports one from LeRobot. With
//! `--write-servos` it also stores in each servo's EEPROM the homing offset
//! that keeps its range off the 4095 -> 0 seam. `play` and `bench` use the
//! refusal check at the end of this file before they move anything.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use servobus_config::{
    load_calibration, load_robot, save_calibration, utc_now, Calibration, Robot, RobotOptions,
};
use servobus_robot::calibrate::{
    calibrate, from_lerobot, store_in_servos, to_lerobot, ProcedureOptions, Store, StoreEnd,
    Stored, PATIENCE, PATIENT_RETRIES,
};

use crate::shared::out::{errln, outln};
use crate::shared::ports::{every_port, Allowance, Ports, SerialBus};

mod screen;

use screen::Terminal;

/// Arguments of `servobus calibrate`.
#[derive(Debug, clap::Args)]
#[command(
    mut_arg("port", |a| a.help(
        "Serial port of the servos, for the robot's first bus (default: the robot file's ports)"
    )),
    mut_arg("calibration", |a| a.help(
        "With --to-lerobot alone: the calibration to export (default: the robot file's)"
    ))
)]
pub struct Args {
    /// The robot, its servos' port, and (with --to-lerobot alone) the
    /// calibration to export.
    #[command(flatten)]
    pub robot: crate::shared::flags::RobotArgs,
    /// Where to write the calibration (default: the file the robot file's
    /// `calibration:` names, else `<robot name>.calibration.yaml`).
    #[arg(short = 'o', long = "output")]
    pub output: Option<PathBuf>,
    /// Also store in each servo's EEPROM (unlock, write, verify, lock) the
    /// homing offset that centres its range, and position limits at it.
    #[arg(long)]
    pub write_servos: bool,
    /// End each step on its own, once the robot has moved and then been held
    /// still for 2 s (as when stdin is not a terminal).
    #[arg(long)]
    pub yes: bool,
    /// Import a LeRobot calibration file instead of calibrating.
    #[arg(long, value_name = "JSON")]
    pub from_lerobot: Option<PathBuf>,
    /// Also write the calibration as a LeRobot calibration file.
    #[arg(long, value_name = "JSON")]
    pub to_lerobot: Option<PathBuf>,
}

/// Runs `servobus calibrate`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let design = load_robot(&args.robot.path, &RobotOptions::design())?;
    let named = design.calibration.file().map(Path::to_owned);
    let output = args
        .output
        .clone()
        .or(named.clone())
        .unwrap_or_else(|| PathBuf::from(format!("{}.calibration.yaml", design.name)));
    let ports = ports(&args, &design)?;
    // The outputs are checked before the procedure, which they would
    // otherwise lose at its end; nothing is created or changed yet.
    let exporting_only = ports.is_none() && args.from_lerobot.is_none();
    if !exporting_only {
        crate::shared::flags::check_writable("-o", &output)?;
    }
    if let Some(out) = &args.to_lerobot {
        crate::shared::flags::check_writable("--to-lerobot", out)?;
    }
    let (cal, unfinished) = if let Some(json) = &args.from_lerobot {
        if args.write_servos && ports.is_none() {
            return Err(crate::shared::exit::input(
                "--write-servos needs the servos' --port",
            ));
        }
        let text = std::fs::read_to_string(json)
            .with_context(|| format!("--from-lerobot: cannot read {}", json.display()))
            .map_err(crate::shared::exit::invalid)?;
        let cal = from_lerobot(&design, &text, &format!("imported from {}", json.display()))
            .with_context(|| json.display().to_string())
            .map_err(crate::shared::exit::invalid)?;
        match (&ports, args.write_servos) {
            (Some(ports), true) => write_imported(&design, ports, cal)?,
            _ => (cal, None),
        }
    } else if let Some(ports) = ports {
        measure(&args, &design, &ports)?
    } else if let Some(out) = &args.to_lerobot {
        let from = args
            .robot
            .hardware
            .calibration
            .clone()
            .or(named)
            .ok_or_else(|| {
                crate::shared::exit::input(
                    "--to-lerobot alone exports a calibration: give --calibration FILE \
                 (the robot file names none)",
                )
            })?;
        let cal = load_calibration(&from)?;
        write_lerobot(&cal, out)?;
        return Ok(ExitCode::SUCCESS);
    } else {
        return Err(crate::shared::exit::input(
            "nothing to calibrate on: give --port (the servos' serial port), \
             or --from-lerobot FILE to import a LeRobot calibration",
        ));
    };
    // Replaced whole or not at all: a failure leaves an earlier calibration
    // at the path untouched.
    save_calibration(&cal, &output)?;
    if let Some(unfinished) = unfinished {
        // What was measured is kept, in the frames the servos now hold.
        outln!("calibration: {}", output.display())?;
        return Err(unfinished.error());
    }
    // Applying it now shows at once a calibration the robot cannot use.
    let robot = load_robot(
        &args.robot.path,
        &RobotOptions::default().calibration(Some(&output)),
    )?;
    print_summary(&robot, &output)?;
    if named.as_deref() != Some(output.as_path()) {
        outln!("to use it: {}", how_to_use(&args.robot.path, &output))?;
    }
    if let Some(out) = &args.to_lerobot {
        write_lerobot(&cal, out)?;
    }
    Ok(ExitCode::SUCCESS)
}

fn write_lerobot(cal: &Calibration, out: &Path) -> anyhow::Result<()> {
    servobus_robot::files::write_atomic(out, to_lerobot(cal).as_bytes())?;
    outln!("LeRobot calibration: {}", out.display())?;
    Ok(())
}

/// One port per bus: `--port` for the first, the robot file's for the
/// rest; `None` when no bus has one.
///
/// # Errors
/// An input error naming the first bus without a port, when only some have
/// one.
fn ports(args: &Args, robot: &Robot) -> anyhow::Result<Option<Vec<String>>> {
    match every_port(robot, args.robot.hardware.port.as_slice()) {
        Ports::None => Ok(None),
        Ports::Every(ports) => Ok(Some(ports)),
        Ports::Missing(bus) => Err(crate::shared::ports::no_port(robot, &bus.name, None)),
    }
}

/// The robot's buses on `ports`, patient: calibrating is not timed.
fn open(robot: &Robot, ports: &[String]) -> anyhow::Result<Vec<SerialBus>> {
    let patient = Allowance::AtLeast(PATIENCE);
    crate::shared::ports::open_buses(robot, ports, patient, Some(PATIENT_RETRIES))
}

/// A store in the servos that ended before the last servo.
struct Unfinished {
    written: Vec<String>,
    not_written: Vec<String>,
    ended: StoreEnd,
}

impl Unfinished {
    /// The error the command ends with (exit 1): why it ended, which
    /// servos were written and which were left as they were.
    fn error(self) -> anyhow::Error {
        let list = |names: &[String]| {
            if names.is_empty() {
                "none".to_owned()
            } else {
                names.join(", ")
            }
        };
        let what = format!(
            "servos written (unlocked, written, verified, locked): {}; not written (left as they \
             were): {}",
            list(&self.written),
            list(&self.not_written)
        );
        match self.ended {
            StoreEnd::Stopped(signal) => anyhow::anyhow!(
                "stopped by {signal} while writing the servos (each servo begun was finished \
                 first): {what}"
            ),
            StoreEnd::Failed(e) => anyhow::Error::new(e).context(what),
            _ => anyhow::anyhow!("writing the servos ended early: {what}"),
        }
    }
}

/// A calibration, and how storing it in the servos ended when it ended
/// before the last one.
type Taken = (Calibration, Option<Unfinished>);

fn measure(args: &Args, robot: &Robot, ports: &[String]) -> anyhow::Result<Taken> {
    let mut buses = open(robot, ports)?;
    let interactive = !args.yes && std::io::stdin().is_terminal();
    let mut operator = Terminal::new(robot, interactive);
    let options = ProcedureOptions {
        auto: !interactive,
        taken: utc_now(),
        ..ProcedureOptions::default()
    };
    let cal = calibrate(robot, &mut buses, &mut operator, &options)?;
    if !args.write_servos {
        return Ok((cal, None));
    }
    store(robot, &mut buses, cal, Store::Centred)
}

/// Stores an imported calibration in the servos as LeRobot does: each
/// servo's homing offset and position limits, in the frame it is played in.
fn write_imported(robot: &Robot, ports: &[String], cal: Calibration) -> anyhow::Result<Taken> {
    // Caught from here: a signal while the ports open writes no servo and
    // still says so (see `store`).
    catch_signals();
    let mut buses = open(robot, ports)?;
    store(robot, &mut buses, cal, Store::PlayFrame)
}

/// From here on SIGINT, SIGTERM and SIGHUP only set the flag the store
/// reads between two servos.
fn catch_signals() {
    if let Err(e) = servobus_robot::bus::catch_stop_signals() {
        errln!("warning: a signal will end the program between two servos ({e})");
    }
}

/// [`store_in_servos`], saying each servo as it is stored.
///
/// From here on SIGINT, SIGTERM and SIGHUP are caught: each servo begun is
/// finished (the driver holds them through its transaction), the store
/// ends before the next one, and the calibration is still saved.
fn store(
    robot: &Robot,
    buses: &mut [SerialBus],
    cal: Calibration,
    how: Store,
) -> anyhow::Result<Taken> {
    catch_signals();
    let Stored {
        calibration,
        written,
        not_written,
        ended,
    } = store_in_servos(robot, buses, cal, how, |joint, jc| {
        // Said as each servo is locked; stdout gone is no reason to stop
        // half way through the arm.
        let _ = outln!(
            "servo {} ({}): Homing_Offset {}, limits {}..{} (unlocked, written, verified, locked)",
            joint.id,
            joint.name,
            jc.homing_offset,
            jc.range[0],
            jc.range[1]
        );
    });
    let unfinished = ended.map(|ended| Unfinished {
        written,
        not_written,
        ended,
    });
    Ok((calibration, unfinished))
}

/// How to name the calibration at `output` for the robot file at `robot`:
/// the `calibration:` line with the path as the robot file reads it
/// (relative to its own directory), or, for a built-in robot, `--calibration`.
fn how_to_use(robot: &Path, output: &Path) -> String {
    let flag = format!(
        "give --calibration {} to the commands that move or read joints",
        output.display()
    );
    if servobus_config::is_builtin_path(robot) {
        return format!(
            "{flag} (or `servobus init` for a robot file of your own, and \
             `calibration: FILE` in it)"
        );
    }
    let dir = robot
        .canonicalize()
        .ok()
        .and_then(|r| r.parent().map(Path::to_path_buf));
    let cal = output.canonicalize().ok();
    let line = match (dir, cal) {
        (Some(dir), Some(cal)) => relative(&dir, &cal),
        _ => output.to_path_buf(),
    };
    format!(
        "add `calibration: {}` to {}, or {flag}",
        line.display(),
        robot.display()
    )
}

/// `target` as a path relative to the directory `base` (both absolute).
fn relative(base: &Path, target: &Path) -> PathBuf {
    let base: Vec<_> = base.components().collect();
    let target: Vec<_> = target.components().collect();
    let common = base.iter().zip(&target).take_while(|(a, b)| a == b).count();
    let mut out = PathBuf::new();
    for _ in common..base.len() {
        out.push("..");
    }
    for c in &target[common..] {
        out.push(c);
    }
    out
}

fn print_summary(robot: &Robot, output: &Path) -> Result<(), crate::shared::out::StdoutError> {
    outln!("calibration: {}", output.display())?;
    for joint in robot.joints() {
        let Some(c) = &joint.calibration else {
            continue;
        };
        let seam = if c.crosses_seam() {
            "  (across the seam: played with a homing offset set for the session)"
        } else {
            ""
        };
        outln!(
            "  {:<16} servo {:>3}  direction {:+}  ticks {}..{}  limits {:.1}..{:.1} {}{seam}",
            joint.name,
            joint.id,
            c.direction,
            c.range[0],
            c.range[1],
            joint.min,
            joint.max,
            robot.units
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hint_names_the_calibration_as_the_robot_file_reads_it() {
        assert_eq!(
            relative(Path::new("/home/a/f"), Path::new("/home/a/cal/c.yaml")),
            PathBuf::from("../cal/c.yaml")
        );
        assert_eq!(
            relative(Path::new("/home/a/f"), Path::new("/home/a/f/c.yaml")),
            PathBuf::from("c.yaml")
        );
        let dir = std::env::temp_dir().join(format!("servobus-hint-{}", std::process::id()));
        let (f, cal) = (dir.join("f"), dir.join("cal"));
        std::fs::create_dir_all(&f).expect("dirs");
        std::fs::create_dir_all(&cal).expect("dirs");
        std::fs::write(f.join("robot.yaml"), "").expect("robot file");
        std::fs::write(cal.join("c.yaml"), "").expect("calibration");
        let hint = how_to_use(&f.join("robot.yaml"), &cal.join("c.yaml"));
        assert!(hint.contains("`calibration: ../cal/c.yaml`"), "{hint}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
