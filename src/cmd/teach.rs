//! `servobus teach`: pose the robot by hand and get a motion file back.

use std::io::{BufRead, IsTerminal, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;

use anyhow::{bail, Context};
use servobus_config::limits::Fixed;
use servobus_config::{load_robot, LimitOrigin, Robot, RobotOptions};
use servobus_robot::bus::Transport;
use servobus_robot::teach::{
    check_pose, distance, motion_yaml, StillCapture, Take, TeachError, Teacher,
};

use crate::shared::out::{err, errln};
use crate::shared::ports::{bus_ports, every_port, Allowance, SerialBus};

/// How often the pose is read in pose-and-pause mode.
const POSE_RATE_HZ: f64 = 50.0;
/// Tries per transaction: a reply lost now and then (a busy pty, a noisy
/// bus) must not end a take.
const RETRIES: u8 = 2;
/// Pose reads that may fail in a row before the take ends with an error.
const MISSED_POSES: u32 = 25;
/// How often the live view is redrawn.
const VIEW_EVERY: Duration = Duration::from_millis(250);

/// Arguments of `servobus teach`.
#[derive(Debug, clap::Args)]
#[command(mut_arg("port", |a| a.help(
    "Serial port of the robot's first bus (default: the robot file's). A simulated robot \
     with a hand: `servobus sim --robot F --hand H --link L`"
)))]
pub struct Args {
    /// The robot, its port and calibration: taught angles are physical
    /// angles when it has one.
    #[command(flatten)]
    pub robot: crate::shared::flags::RobotArgs,
    /// The motion file to write.
    #[arg(short = 'o', long = "output", value_name = "MOTION.yaml")]
    pub output: PathBuf,
    /// Joints that keep their position with torque on (e.g. a shoulder
    /// that would fall), comma-separated.
    #[arg(long, value_delimiter = ',', value_name = "JOINT,...")]
    pub hold: Vec<String>,
    /// Record the whole path at the control rate and reduce it to the
    /// fewest timed keyframes that reproduce it (instead of pose-and-pause).
    #[arg(long)]
    pub continuous: bool,
    /// With --continuous: how closely the keyframes must reproduce the
    /// path, degrees.
    #[arg(long, default_value = "0.5", value_name = "DEG", value_parser = crate::shared::args::tolerance_deg_arg)]
    pub tolerance: f64,
    /// Stop after this many seconds.
    #[arg(long, value_name = "S", value_parser = crate::shared::args::run_seconds_arg)]
    pub duration: Option<Duration>,
    /// No keyboard: capture a keyframe whenever the robot has moved and
    /// then been held still for 0.7 s (also when stdin is not a terminal).
    #[arg(long)]
    pub yes: bool,
}

/// Runs `servobus teach`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let robot = load_robot(
        &args.robot.path,
        &RobotOptions::default().calibration(args.robot.hardware.calibration.as_deref()),
    )?;
    // Check the output before anything moves, without emptying a file that
    // is there: it is replaced only once something has been captured.
    crate::shared::flags::check_writable("-o", &args.output)?;
    let port = args.robot.hardware.port.as_deref();
    let buses = open_buses(&robot, port)?;
    // The servos are made to match the calibration before the first pose is
    // read: a taught angle is the angle `play` moves to.
    let mut teacher = Teacher::new(&robot, buses, &args.hold).map_err(|e| match e {
        TeachError::Refused(refusal) => {
            let port = bus_ports(&robot, port.as_slice())
                .into_iter()
                .flatten()
                .next();
            crate::shared::refused(&robot, &refusal, port.as_deref().unwrap_or("PORT"))
        }
        e => e.into(),
    })?;
    teacher.release()?;
    let held = if args.hold.is_empty() {
        String::new()
    } else {
        format!(" (holding {})", args.hold.join(", "))
    };
    let interactive = std::io::stdin().is_terminal() && !args.yes;
    errln!("torque off{held}: move the robot by hand.");
    errln!("{}", how_to_stop(&args, interactive));

    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst))
        .context("cannot install the SIGINT/SIGTERM handler")?;
    let keys = interactive.then(stdin_lines);

    let taken = take(&args, &robot, &mut teacher, &stop, keys.as_ref());
    // Nothing is lost: what was captured (inside the limits) is written even
    // after an error.
    let taught = match &taken {
        Ok(t) | Err((t, _)) => t.taught(&robot, args.continuous, args.tolerance),
    };
    let taught = match (taught, taken) {
        (Ok(Some(taught)), taken) => (taught, taken),
        (Ok(None), Err((_, e))) => return Err(explain(e, None)),
        (Ok(None), Ok(_)) => bail!("nothing was captured; no motion file written"),
        (Err(e), _) => {
            return Err(anyhow::Error::new(e).context("the take is not written: nothing was"))
        }
    };
    let (taught, taken) = taught;
    // A built-in robot by its name, a file relative to the motion: the
    // motion plays again where it is moved with its robot file.
    let robot_file = servobus::builtin::motion_robot_field(&args.robot.path, &args.output);
    let yaml = motion_yaml(&robot, &robot_file, &taught);
    // Whole or not at all: a failed write leaves no partial motion file,
    // and an earlier file at the path as it was.
    servobus_robot::files::write_atomic(&args.output, yaml.as_bytes())?;
    let written = format!(
        "wrote {} keyframe{} to {}",
        taught.keyframes.len(),
        if taught.keyframes.len() == 1 { "" } else { "s" },
        args.output.display()
    );
    match taken {
        Ok(_) => {
            // The port the take was on, named: `play` without `--port` on a
            // robot file without `port:` moves the simulator, not this arm.
            let replay = match port {
                Some(port) => format!("servobus play {} --port {port}", args.output.display()),
                None => format!("servobus play {}", args.output.display()),
            };
            errln!("{written}; play it on the same servos with `{replay}`");
            Ok(ExitCode::SUCCESS)
        }
        Err((_, e)) => Err(explain(e, Some(&written))),
    }
}

/// What to do about a take that stopped on `e`; `written` says what was
/// kept of it.
fn explain(e: anyhow::Error, written: Option<&str>) -> anyhow::Error {
    let kept = written.map_or_else(
        || "nothing was written".to_owned(),
        |w| format!("the keyframes before it are kept: {w}"),
    );
    match e.downcast_ref::<TeachError>() {
        Some(TeachError::OutsideLimits { origin, .. }) => {
            let widen = match origin {
                LimitOrigin::RobotFile => {
                    "to allow it, widen `min`/`max` of the joint in the robot file"
                }
                LimitOrigin::Calibration => {
                    "if the joint really reaches there, calibrate again, sweeping it to its end stops"
                }
            };
            anyhow::anyhow!(
                "{e}.\nThe take stopped there and {kept}. Keep the joint inside its limits and \
                 teach again ({widen})."
            )
        }
        _ => anyhow::anyhow!(
            "{}\nThe take stopped and {kept}.",
            crate::shared::exit::message(&e)
        ),
    }
}

fn how_to_stop(args: &Args, interactive: bool) -> String {
    let mut ways = vec!["Ctrl-C".to_owned()];
    if interactive {
        ways.insert(0, "Enter without moving (or q)".to_owned());
    }
    if let Some(d) = args.duration {
        ways.push(format!("after {} s", d.as_secs_f64()));
    }
    let what = match (args.continuous, interactive) {
        (true, _) => "Recording the path.",
        (false, true) => "Press Enter to capture a keyframe.",
        (false, false) => "A keyframe is captured each time the robot is held still for 0.7 s.",
    };
    format!("{what} Stops on {}.", ways.join(", "))
}

/// The buses of `robot`: `port` for the first, the robot file's for the rest.
fn open_buses(robot: &Robot, port: Option<&str>) -> anyhow::Result<Vec<SerialBus>> {
    let ports = every_port(robot, port.as_slice())
        .required(robot)
        .map_err(|e| match e {
            servobus_robot::Error::NoPort { bus } => {
                let sim = format!(
                    "a simulated robot: `servobus sim --robot {} --hand H.yaml --link L`",
                    robot.path.display()
                );
                crate::shared::ports::no_port(robot, &bus, Some(&sim))
            }
            e => e.into(),
        })?;
    crate::shared::ports::open_buses(robot, &ports, Allowance::Assumed, Some(RETRIES))
}

/// Lines typed on stdin, read on their own thread.
fn stdin_lines() -> mpsc::Receiver<String> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::stdin().lock().lines() {
            let Ok(line) = line else { return };
            if tx.send(line).is_err() {
                return;
            }
        }
    });
    rx
}

type Taken = Result<Take, (Take, anyhow::Error)>;

/// Reads the pose until told to stop, capturing keyframes or the path.
fn take<T: Transport>(
    args: &Args,
    robot: &Robot,
    teacher: &mut Teacher<T>,
    stop: &AtomicBool,
    keys: Option<&mpsc::Receiver<String>>,
) -> Taken {
    let mut take = Take::default();
    let rate = if args.continuous {
        robot.rate_hz
    } else {
        POSE_RATE_HZ
    };
    let period = Duration::from_secs_f64(1.0 / rate);
    let start = teacher.now();
    let end = args.duration.map(|d| start + d);
    let first = match teacher
        .pose()
        .and_then(|p| check_pose(robot, &p).map(|()| p))
    {
        Ok(p) => p,
        Err(e) => return Err((take, e.into())),
    };
    take.start = Some(first.clone());
    let mut taking = Taking {
        args,
        robot,
        stop,
        keys,
        capture: StillCapture::new(&first, robot.units),
        names: teacher.joint_names(),
        view: std::io::stderr().is_terminal(),
        take,
    };
    let mut next = start;
    let mut next_view = start;
    let mut missed = 0;
    while !stop.load(Ordering::SeqCst) && end.is_none_or(|e| teacher.now() < e) {
        next += period;
        let now = teacher.now();
        if next < now {
            next = now;
        }
        teacher.sleep_until(next);
        let pose = match teacher.pose() {
            Ok(p) => {
                missed = 0;
                p
            }
            Err(_) if missed < MISSED_POSES => {
                missed += 1;
                continue;
            }
            Err(e) => return Err((taking.take, e.into())),
        };
        let t = (teacher.now() - start).as_secs_f64();
        if let Err(e) = taking.sample(t, &pose) {
            return Err((taking.take, e.into()));
        }
        if taking.view && teacher.now() >= next_view {
            next_view = teacher.now() + VIEW_EVERY;
            err!("\r\x1b[K{t:6.1} s  {}", show(&taking.names, &pose));
            let _ = std::io::stderr().flush();
        }
    }
    if taking.view {
        errln!();
    }
    Ok(taking.take)
}

/// A take in progress: what each pose read adds to it.
struct Taking<'a> {
    args: &'a Args,
    robot: &'a Robot,
    /// Set to end the take (Enter without moving, `q`, Ctrl-C).
    stop: &'a AtomicBool,
    /// Lines typed, when interactive.
    keys: Option<&'a mpsc::Receiver<String>>,
    capture: StillCapture,
    names: Vec<String>,
    /// The live view is drawn (stderr is a terminal).
    view: bool,
    take: Take,
}

impl Taking<'_> {
    /// Adds the pose read at `t` s: a point of the path, a keyframe, or
    /// nothing.
    fn sample(&mut self, t: f64, pose: &[f64]) -> Result<(), TeachError> {
        if self.args.continuous {
            // Every sample is a point of the path: none leaves the limits.
            check_pose(self.robot, pose)?;
            self.take.samples.push((t, pose.to_vec()));
        }
        match self.captured(t, pose) {
            Some(k) => self.keyframe(t, k),
            None => Ok(()),
        }
    }

    /// The keyframe this pose makes, if any: Enter pressed when
    /// interactive, else the robot held still; a key may end the take.
    fn captured(&mut self, t: f64, pose: &[f64]) -> Option<Vec<f64>> {
        let mut captured = None;
        if let Some(keys) = self.keys {
            while let Ok(line) = keys.try_recv() {
                let still = distance(pose, self.capture.last()) <= self.capture.moved;
                if self.args.continuous
                    || line.trim() == "q"
                    || (still && !self.take.poses.is_empty())
                {
                    self.stop.store(true, Ordering::SeqCst);
                } else {
                    self.capture.captured(pose);
                    captured = Some(pose.to_vec());
                }
            }
        } else if !self.args.continuous {
            captured = self.capture.push(t, pose);
        }
        captured
    }

    /// Adds keyframe `k`, captured at `t` s, once inside the limits, and
    /// says so.
    fn keyframe(&mut self, t: f64, k: Vec<f64>) -> Result<(), TeachError> {
        check_pose(self.robot, &k)?;
        self.take.poses.push((t, k.clone()));
        errln!(
            "{}keyframe {} at {t:.1} s: {}",
            if self.view { "\r\x1b[K" } else { "" },
            self.take.poses.len(),
            show(&self.names, &k)
        );
        Ok(())
    }
}

fn show(names: &[String], pose: &[f64]) -> String {
    names
        .iter()
        .zip(pose)
        .map(|(n, v)| format!("{n} {}", Fixed(*v, 1)))
        .collect::<Vec<_>>()
        .join("  ")
}
