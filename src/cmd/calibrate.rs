//! `servobus calibrate`: where one physical robot's joints really are.
//!
//! Runs the procedure of [`servobus_runtime::calibrate`] on the robot's
//! servos (torque off, the calibration pose held, every joint swept) and
//! writes the calibration file; or imports one from LeRobot. With
//! `--write-servos` it also stores in each servo's EEPROM the homing offset
//! that keeps its range off the 4095 -> 0 seam. `play` and `bench` use the
//! refusal check at the end of this file before they move anything.

use std::io::{BufRead, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use anyhow::Context;
use servobus_driver::{Bus, Clock, Transport};
use servobus_runtime::calibrate::{
    calibrate, from_lerobot, prepare_bus, to_lerobot, write_frame, write_homing, LiveJoint,
    Operator, ProcedureOptions, Refusal, Step,
};
use servobus_runtime::config::{
    load_calibration, load_robot_calibrated, load_robot_design, save_calibration, utc_now,
    Calibration, Robot, RobotCalibration,
};

use super::link::{every_port, open_bus, Allowance, Ports, SerialBus};

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
    pub robot: super::RobotArgs,
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
    let (design, named) = load_robot_design(&args.robot.path)?;
    let output = args
        .output
        .clone()
        .or(named.clone())
        .unwrap_or_else(|| PathBuf::from(format!("{}.calibration.yaml", design.name)));
    let ports = ports(&args, &design)?;
    let cal = if let Some(json) = &args.from_lerobot {
        if args.write_servos && ports.is_none() {
            return Err(super::exit::input(
                "--write-servos needs the servos' --port",
            ));
        }
        let text = std::fs::read_to_string(json)
            .with_context(|| format!("--from-lerobot: cannot read {}", json.display()))
            .map_err(super::exit::invalid)?;
        let cal = from_lerobot(&design, &text, &format!("imported from {}", json.display()))
            .with_context(|| json.display().to_string())
            .map_err(super::exit::invalid)?;
        match (&ports, args.write_servos) {
            (Some(ports), true) => write_imported(&design, ports, cal)?,
            _ => cal,
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
                super::exit::input(
                    "--to-lerobot alone exports a calibration: give --calibration FILE \
                 (the robot file names none)",
                )
            })?;
        let cal = load_calibration(&from)?;
        write_lerobot(&cal, out)?;
        return Ok(ExitCode::SUCCESS);
    } else {
        return Err(super::exit::input(
            "nothing to calibrate on: give --port (the servos' serial port), \
             or --from-lerobot FILE to import a LeRobot calibration",
        ));
    };
    save_calibration(&cal, &output)
        .with_context(|| format!("cannot write {}", output.display()))?;
    // Applying it now shows at once a calibration the robot cannot use.
    let robot = load_robot_calibrated(&args.robot.path, Some(&output))?;
    print_summary(&robot, &output);
    if named.as_deref() != Some(output.as_path()) {
        println!(
            "to use it: add `calibration: {}` to {} (relative to it), or give --calibration {} \
             to play and bench",
            output.display(),
            args.robot.path.display(),
            output.display()
        );
    }
    if let Some(out) = &args.to_lerobot {
        write_lerobot(&cal, out)?;
    }
    Ok(ExitCode::SUCCESS)
}

fn write_lerobot(cal: &Calibration, out: &Path) -> anyhow::Result<()> {
    std::fs::write(out, to_lerobot(cal))
        .with_context(|| format!("cannot write {}", out.display()))?;
    println!("LeRobot calibration: {}", out.display());
    Ok(())
}

/// One port per bus: `--port` for the first, the robot file's for the
/// rest; `None` when no bus has one.
///
/// # Errors
/// An input error naming the first bus without a port, when only some have
/// one.
fn ports(args: &Args, robot: &Robot) -> anyhow::Result<Option<Vec<String>>> {
    match every_port(robot, args.robot.hardware.port.as_deref()) {
        Ports::None => Ok(None),
        Ports::Every(ports) => Ok(Some(ports)),
        Ports::Missing(bus) => Err(super::exit::input(format!(
            "bus `{}` of {} has no port: every bus of the robot needs one (`port:` in the \
             robot file; --port sets the first bus's)",
            bus.name,
            robot.path.display()
        ))),
    }
}

/// Reply deadline allowance: calibrating and the checks before a run are
/// not timed, so a slow adapter or a loaded host (a pty served by a process
/// that waits for the CPU) must not make a present servo look absent. A
/// servo that is really missing costs this much per try, once.
const PATIENCE: Duration = Duration::from_millis(50);

/// Tries per transaction while calibrating: a reply lost now and then must
/// not end the procedure.
const RETRIES: u8 = 3;

fn open(robot: &Robot, ports: &[String]) -> anyhow::Result<Vec<SerialBus>> {
    let mut buses = Vec::new();
    for (bus, port) in robot.buses.iter().zip(ports) {
        let mut opened = open_bus(bus, port, Allowance::AtLeast(PATIENCE))?;
        opened.set_settings(opened.settings().with_retries(RETRIES));
        buses.push(opened);
    }
    Ok(buses)
}

fn measure(args: &Args, robot: &Robot, ports: &[String]) -> anyhow::Result<Calibration> {
    let mut buses = open(robot, ports)?;
    let interactive = !args.yes && std::io::stdin().is_terminal();
    let mut operator = Terminal::new(robot, interactive);
    let options = ProcedureOptions {
        auto: !interactive,
        taken: utc_now(),
        ..ProcedureOptions::default()
    };
    let mut cal = calibrate(robot, &mut buses, &mut operator, &options)?;
    if args.write_servos {
        let mut i = 0;
        for (bus, config) in buses.iter_mut().zip(&robot.buses) {
            for joint in &config.joints {
                let Some(jc) = cal.joints.get_mut(i) else {
                    break;
                };
                *jc = write_homing(bus, joint, jc)
                    .with_context(|| format!("joint `{}`: writing the EEPROM", joint.name))?;
                println!(
                    "servo {} ({}): Homing_Offset {}, limits {}..{} (unlocked, written, verified, locked)",
                    joint.id, joint.name, jc.homing_offset, jc.range[0], jc.range[1]
                );
                i += 1;
            }
        }
    }
    Ok(cal)
}

/// Stores an imported calibration in the servos as LeRobot does: each
/// servo's homing offset and position limits, in the frame it is played in.
fn write_imported(
    robot: &Robot,
    ports: &[String],
    mut cal: Calibration,
) -> anyhow::Result<Calibration> {
    let mut buses = open(robot, ports)?;
    let mut joints = cal.joints.iter_mut();
    for (bus, config) in buses.iter_mut().zip(&robot.buses) {
        for joint in &config.joints {
            let Some(jc) = joints.next() else { break };
            *jc = write_frame(bus, joint, jc, jc.play_frame())
                .with_context(|| format!("joint `{}`: writing the EEPROM", joint.name))?;
            println!(
                "servo {} ({}): Homing_Offset {}, limits {}..{} (unlocked, written, verified, locked)",
                joint.id, joint.name, jc.homing_offset, jc.range[0], jc.range[1]
            );
        }
    }
    Ok(cal)
}

fn print_summary(robot: &Robot, output: &Path) {
    println!("calibration: {}", output.display());
    for joint in robot.joints() {
        let Some(c) = &joint.calibration else {
            continue;
        };
        let seam = if c.crosses_seam() {
            "  (across the seam: played with a homing offset set for the session)"
        } else {
            ""
        };
        println!(
            "  {:<16} servo {:>3}  direction {:+}  ticks {}..{}  limits {:.1}..{:.1} {}{seam}",
            joint.name,
            joint.id,
            c.direction,
            c.range[0],
            c.range[1],
            joint.min,
            joint.max,
            robot.units
        );
    }
}

/// The person at the terminal (or, without one, the robot's stillness).
struct Terminal {
    names: Vec<String>,
    deg_per_tick: Vec<f64>,
    pose: String,
    interactive: bool,
    live: bool,
    entered: Arc<AtomicBool>,
    shown: Option<Duration>,
    lines: usize,
}

impl Terminal {
    fn new(robot: &Robot, interactive: bool) -> Self {
        let entered = Arc::new(AtomicBool::new(false));
        if interactive {
            let flag = Arc::clone(&entered);
            std::thread::spawn(move || {
                for line in std::io::stdin().lock().lines() {
                    if line.is_err() {
                        break;
                    }
                    flag.store(true, Ordering::SeqCst);
                }
            });
        }
        let pose = robot
            .joints()
            .zip(&robot.calibration_pose)
            .map(|(j, p)| format!("{} {p}", j.name))
            .collect::<Vec<_>>()
            .join(", ");
        Terminal {
            names: robot.joints().map(|j| j.name.clone()).collect(),
            deg_per_tick: robot.joints().map(|j| j.model.deg_per_tick()).collect(),
            pose: format!("{pose} ({})", robot.units),
            interactive,
            live: std::io::stdout().is_terminal(),
            entered,
            shown: None,
            lines: 0,
        }
    }

    fn ends(&self) -> &'static str {
        if self.interactive {
            "Press Enter when done."
        } else {
            "The step ends once the robot has moved and then been held still for 2 s."
        }
    }
}

impl Operator for Terminal {
    fn step(&mut self, step: Step) {
        self.shown = None;
        self.lines = 0;
        let text = match step {
            Step::TorqueOff => {
                "1. Torque is off on every servo: the joints move freely. Support the robot."
                    .to_owned()
            }
            Step::HoldPose => format!(
                "2. Hold the robot in its calibration pose (see the robot file): {}. {}",
                self.pose,
                self.ends()
            ),
            Step::Sweep => format!(
                "3. Move every joint first towards positive angles, then through its whole range, \
                 end stop to end stop; then back to the pose. {}",
                self.ends()
            ),
            Step::Done => "4. Done: writing the calibration.".to_owned(),
        };
        println!("{text}");
        let _ = std::io::stdout().flush();
    }

    fn watch(&mut self, at: Duration, joints: &[LiveJoint]) {
        let every = if self.live { 100 } else { 2000 };
        if self
            .shown
            .is_some_and(|s| at < s + Duration::from_millis(every))
        {
            return;
        }
        self.shown = Some(at);
        let mut out = String::new();
        if self.live && self.lines > 0 {
            out.push_str(&format!("\x1b[{}A", self.lines));
        }
        // Escape codes (clear to the end of the line) only on a terminal.
        let clear = if self.live { "\x1b[K" } else { "" };
        for ((name, j), dpt) in self.names.iter().zip(joints).zip(&self.deg_per_tick) {
            out.push_str(&format!(
                "  {name:<16} min {:>6}  max {:>6}  now {:>6}  ({:.0} deg swept){clear}\n",
                j.min,
                j.max,
                j.now,
                (j.max - j.min) as f64 * dpt
            ));
        }
        self.lines = joints.len();
        print!("{out}");
        let _ = std::io::stdout().flush();
    }

    fn confirmed(&mut self) -> bool {
        self.entered.swap(false, Ordering::SeqCst)
    }
}

/// Before `play` or `bench` moves real servos: stops when the robot's
/// calibration is missing or does not fit the servos on bus `index`, with
/// what to run; otherwise puts the servos in their play frame.
pub(crate) fn check_bus<T: Transport, C: Clock>(
    robot: &Robot,
    index: usize,
    bus: &mut Bus<T, C>,
    port: &str,
) -> anyhow::Result<()> {
    // Not timed: patient deadlines, so that a slow adapter or a loaded host
    // does not make a servo look absent; the run's own settings after.
    let saved = *bus.settings();
    bus.set_settings(
        saved
            .with_latency(saved.link.latency.max(PATIENCE))
            .with_retries(RETRIES),
    );
    let checked = prepare_bus(robot, index, bus);
    bus.set_settings(saved);
    checked.map_err(|refusal| refused(robot, &refusal, port))
}

/// [`check_bus`] for every bus.
pub(crate) fn check_buses<T: Transport, C: Clock>(
    robot: &Robot,
    buses: &mut [Bus<T, C>],
    ports: &[String],
) -> anyhow::Result<()> {
    for (i, (bus, port)) in buses.iter_mut().zip(ports).enumerate() {
        check_bus(robot, i, bus, port)?;
    }
    Ok(())
}

fn refused(robot: &Robot, refusal: &Refusal, port: &str) -> anyhow::Error {
    let file = match &robot.calibration {
        RobotCalibration::Missing(path) | RobotCalibration::Applied { path, .. } => path.clone(),
        RobotCalibration::None => PathBuf::from(format!("{}.calibration.yaml", robot.name)),
    };
    anyhow::anyhow!(
        "{refusal}\nnothing was moved. Calibrate this robot first:\n  servobus calibrate --robot {} --port {port} -o {}",
        robot.path.display(),
        file.display()
    )
}
