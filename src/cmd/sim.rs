//! `servobus sim`: serve a robot file's simulated servos on a pseudo-terminal.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::Context;
use servobus_config::{load_robot, Robot, RobotOptions};
use servobus_robot::files::OutputError;
use servobus_robot::odometry::{pose_figures, Odometry, TruthBase};
use servobus_robot::sim::{new_truth, Hand, Mounting, SimRobot, SimRobotBuilder, SimRobotError};
use servobus_robot::sim::{Faults, PtyServer, SimServo, Truth};

use crate::shared::flags::Recording;

const FAULTS_HELP: &str = "\
Fault injection: comma-separated items, applied to every reply independently.
  drop=P        a reply is not sent, with probability P (0..1)
  corrupt=P     one byte of a reply is corrupted, with probability P
  delay=P       a reply starts late, with probability P ...
  delay_us=N    ... by N microseconds (default 2000)
  hold=P        a reply sent on time reaches the host late (a loaded machine), with probability P ...
  hold_us=N     ... by N microseconds (default 2000)
  seed=N        seed of the random source (default 0): same seed, same faults
  echo          echo every request back (same as --echo)
  vanish=ID     servo ID is disconnected (repeatable)
  vanish=ID@S   servo ID answers for S seconds from the first byte it hears, then is silent
  block=ID      servo ID's shaft is blocked: overload after the protection time (repeatable)
  overheat=ID   servo ID starts at its temperature limit (repeatable)
  supply=V      every servo's supply at V volts; supply=ID:V for one servo
  firmware=ID:MAJOR.MINOR   servo ID reports another firmware version
  baud=ID:RATE  servo ID listens at another baud rate (e.g. 3:115200)
  duplicate=FROM:TO         servo FROM answers as ID TO (two servos share TO)
Example: --faults drop=0.01,corrupt=0.01,seed=7";

/// Arguments of `servobus sim`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The robot whose servos to serve: a file, or a built-in name.
    #[arg(long, value_parser = crate::shared::flags::robot_arg)]
    pub robot: std::path::PathBuf,
    /// Make this path a symbolic link to the pty (removed on exit).
    #[arg(long)]
    pub link: Option<std::path::PathBuf>,
    /// Do not pace bytes at the wire rate (replies come at once).
    #[arg(long)]
    pub no_pacing: bool,
    /// Fault injection, e.g. `drop=0.01,corrupt=0.01,seed=7` (see --help).
    #[arg(long, long_help = FAULTS_HELP)]
    pub faults: Option<String>,
    /// Echo every request back, as a half-duplex adapter without direction control does.
    #[arg(long)]
    pub echo: bool,
    /// Serve only the bus with this name (default: every bus of the robot
    /// on one pty, at the first bus's baud rate; IDs must then be distinct).
    #[arg(long)]
    pub bus: Option<String>,
    /// How each servo horn sits on its joint: a YAML file of
    /// `<joint>: {zero_tick, direction, stops: [min_deg, max_deg]}`
    /// (built-in: so101-mounting; `servobus list`). Default: the robot file's.
    #[arg(long, value_name = "M.yaml", value_parser = crate::shared::flags::mounting_arg)]
    pub mounting: Option<std::path::PathBuf>,
    /// A randomly assembled unit instead of --mounting: horns anywhere on
    /// the turn (some ranges across the 4095/0 seam), some directions
    /// reversed, stops just past the limits. Same seed, same unit.
    #[arg(long, value_name = "SEED", conflicts_with = "mounting")]
    pub unit: Option<u64>,
    /// A hand that moves torque-off joints along keyframes of physical
    /// angles: `{keyframes: [{at: SECONDS, pose: {<joint>: DEG}}]}`
    /// (built-in: so101-hand; `servobus list`).
    #[arg(long, value_name = "H.yaml", value_parser = crate::shared::flags::hand_arg)]
    pub hand: Option<std::path::PathBuf>,
    /// Write the physical joint angles (deg) to this CSV, `time_s,<joint>,...`,
    /// 100 rows a second, as a live stream: whole rows, flushed at least
    /// every 100 ms while the simulator runs (`tail -f` follows it). The
    /// file is created (or an earlier one truncated) only once the
    /// simulator serves: a simulator refused at start leaves it untouched.
    #[arg(long, value_name = "T.csv")]
    pub truth: Option<std::path::PathBuf>,
    /// `--rerun FILE.rrd`, `--rerun-connect [ADDR]`: the simulator's truth
    /// (the physical joint angles, 100 a second) in the Rerun viewer,
    /// whatever client moves the servos; the file is written whole when
    /// the simulator stops.
    #[command(flatten)]
    pub rerun: crate::shared::flags::RerunArgs,
}

/// How long the truth writer sleeps between passes (rows are sampled every
/// 10 ms): half the 100 ms within which `--help` promises a row is in the
/// file, so that a pass's own time and a late wake-up stay inside it.
const TRUTH_PASS: std::time::Duration = std::time::Duration::from_millis(50);

/// Runs `servobus sim`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let robot = load_robot(&args.robot, &RobotOptions::default())?;
    let faults = faults_of(&args)?;
    let mut builder = builder_of(&args, &robot)?;
    args.rerun.check()?;
    let truth = truth_of(&args, &robot)?;
    if let Some(truth) = &truth {
        builder = builder.truth(truth);
    }
    let rerun = args.rerun.start(&robot, robot.units)?;
    let opened = open_server(&args, &builder, faults, truth.is_some());
    let ((mut server, count), rerun) = rerun.unless_refused(opened)?;
    // Started: the truth file is created (or truncated) now, its header
    // written before the simulator says it serves, so that a reader who
    // opens it then finds at least the header. An error here drops the
    // server, which removes the link.
    // A mobile base's true pose goes with its wheels' angles.
    let base = truth
        .as_ref()
        .and_then(|t| TruthBase::of(&robot, &t.names()));
    let file = match &args.truth {
        Some(path) => Some(create_truth(truth.as_ref(), path, base.is_some())?),
        None => None,
    };
    let truth = truth.map(|truth| Streams {
        columns: columns_of(&robot, &truth.names()),
        joints: robot.joint_count(),
        truth,
        base,
        file,
        rerun,
        units: robot.units,
    });

    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst))
        .context("cannot install the SIGINT/SIGTERM handler")?;

    crate::shared::out::outln!(
        "serving {count} servos on {}",
        server.client_path().display()
    )?;
    crate::shared::out::flush()?;

    let writer = truth.map(|streams| TruthWriter::spawn(streams, &stop));
    let served = server.serve(&stop);
    server.settle();
    // Dropping the server removes the link, also after an I/O error.
    drop(server);
    if let Some(writer) = writer {
        writer.finish()?;
    }
    served?;
    Ok(ExitCode::SUCCESS)
}

/// The faults `--faults` and `--echo` inject.
fn faults_of(args: &Args) -> anyhow::Result<Faults> {
    let mut faults = match &args.faults {
        Some(spec) => spec
            .parse::<Faults>()
            .with_context(|| format!("--faults {spec}"))?,
        None => Faults::none(),
    };
    faults.echo |= args.echo;
    Ok(faults)
}

/// The simulated robot with its mounting (`--mounting`, `--unit`) and hand.
fn builder_of<'a>(args: &Args, robot: &'a Robot) -> anyhow::Result<SimRobotBuilder<'a>> {
    let mut builder = SimRobot::builder(robot);
    if let Some(path) = &args.mounting {
        builder = builder.mounting(Mounting::load(path, robot)?);
    }
    if let Some(seed) = args.unit {
        builder = builder.mounting(Mounting::random(robot, seed));
    }
    if let Some(path) = &args.hand {
        builder = builder.hand(Hand::load(path, robot)?);
    }
    Ok(builder)
}

/// The truth `--truth` writes and `--rerun` records, one column per
/// served joint; `None` when neither is asked for. The truth file's path
/// is checked, not yet opened.
fn truth_of(args: &Args, robot: &Robot) -> anyhow::Result<Option<Truth>> {
    // The truth is a stream that others follow while the simulator runs,
    // so it is written in place, not atomically. Its path is checked now
    // (a directory, a missing directory: refused before anything is
    // served), and the file opened only once the simulator serves (in
    // `run`), so that a simulator refused at start leaves an earlier file
    // as it was.
    if let Some(path) = &args.truth {
        servobus_robot::files::check_output(path)?;
    } else if !args.rerun.wanted() {
        return Ok(None);
    }
    let truth = match args.bus.as_deref() {
        Some(name) => Truth::new(
            robot
                .buses
                .iter()
                .filter(|b| b.name == name)
                .flat_map(|b| b.joints.iter().map(|j| j.name.clone()))
                .collect(),
            servobus_robot::sim::TRUTH_PERIOD,
        ),
        None => new_truth(robot),
    };
    Ok(Some(truth))
}

/// Each truth column's joint, in the robot's joint order.
fn columns_of(robot: &Robot, names: &[String]) -> Vec<Option<usize>> {
    names.iter().map(|n| robot.joint_index(n)).collect()
}

/// The pty server of the served servos, set up as the flags say, and how
/// many servos it serves; `truth`: a truth is sampled.
fn open_server(
    args: &Args,
    builder: &SimRobotBuilder<'_>,
    faults: Faults,
    truth: bool,
) -> anyhow::Result<(PtyServer, usize)> {
    let bodies = args.mounting.is_some() || args.unit.is_some() || args.hand.is_some();
    let (baud, servos) = servos_of(builder, args.bus.as_deref())?;
    let count = servos.len();
    let mut server = PtyServer::open(baud, servos)?;
    if let Some(link) = &args.link {
        server.link_to(link)?;
    }
    server.set_pacing(!args.no_pacing);
    server.set_faults(faults);
    if bodies || truth {
        // Bodies move (and the truth is sampled) while no client talks.
        server.set_tick(Some(servobus_robot::sim::TRUTH_PERIOD));
    }
    Ok((server, count))
}

/// Creates (or truncates) the truth file at `path` and writes its header
/// (the columns of `truth`, and the base's pose with `base`).
fn create_truth(
    truth: Option<&Truth>,
    path: &std::path::Path,
    base: bool,
) -> Result<(std::fs::File, PathBuf), OutputError> {
    let write_err = |source| OutputError::Write {
        path: path.to_owned(),
        source,
    };
    let mut file = std::fs::File::create(path).map_err(write_err)?;
    let mut header = truth.map_or_else(String::new, Truth::csv_header);
    if base {
        for (name, _) in pose_figures(&Odometry::default()) {
            header.push(',');
            header.push_str(name);
        }
    }
    writeln!(file, "{header}").map_err(write_err)?;
    Ok((file, path.to_owned()))
}

/// Where the truth goes while the simulator serves: its CSV file
/// (`--truth`) and the recording for the Rerun viewer (`--rerun`).
struct Streams {
    truth: Truth,
    /// Each column's joint in the robot's order.
    columns: Vec<Option<usize>>,
    /// How many joints the robot has.
    joints: usize,
    base: Option<TruthBase>,
    /// The truth file and its path.
    file: Option<(std::fs::File, PathBuf)>,
    rerun: Recording,
    /// The robot's angle unit, the recording's.
    units: servobus_config::Units,
}

/// The thread that streams the truth to its file and recording while the
/// simulator serves.
struct TruthWriter {
    handle: std::thread::JoinHandle<anyhow::Result<()>>,
    /// Set once the server has made its last step.
    done: Arc<AtomicBool>,
}

impl TruthWriter {
    /// Starts streaming the truth of `streams`, with the base's true pose
    /// on each row when the robot has one.
    fn spawn(streams: Streams, stop: &Arc<AtomicBool>) -> Self {
        let stop = Arc::clone(stop);
        let done = Arc::new(AtomicBool::new(false));
        let finished = Arc::clone(&done);
        let handle = std::thread::spawn(move || -> anyhow::Result<()> {
            let mut streams = streams;
            let written = write_truth(&mut streams, &stop, &finished);
            let recorded = streams.rerun.finish();
            if let (Err(source), Some((_, path))) = (written, streams.file) {
                return Err(OutputError::Write { path, source }.into());
            }
            if let Some(what) = recorded? {
                crate::shared::out::errln!("rerun: {what}");
            }
            Ok(())
        });
        TruthWriter { handle, done }
    }

    /// Writes the last rows and waits for the thread: its error, if any.
    fn finish(self) -> anyhow::Result<()> {
        self.done.store(true, Ordering::SeqCst);
        match self.handle.join() {
            Ok(result) => result,
            Err(_) => anyhow::bail!("the truth writer failed"),
        }
    }
}

/// Streams the truth's complete rows until `done`, every [`TRUTH_PASS`]:
/// to the file, each pass's rows formatted first and handed to it in one
/// write, unbuffered (a reader following the file sees whole rows only,
/// and memory does not grow with a long session); and to the recording,
/// as the robot's measured pose (angles in the robot's unit).
fn write_truth(streams: &mut Streams, stop: &AtomicBool, done: &AtomicBool) -> std::io::Result<()> {
    let mut text = String::new();
    let mut measured: Vec<Option<f64>> = vec![None; streams.joints];
    loop {
        // `done` is set after the server's last step: one more pass then
        // writes every row up to the end.
        let last = done.load(Ordering::SeqCst);
        text.clear();
        for row in streams.truth.take_rows() {
            let pose = streams.base.as_mut().map(|b| b.take(&row));
            push_row(&mut text, row.time_s, &row.angles_deg, pose);
            measured.fill(None);
            for (column, deg) in streams.columns.iter().zip(&row.angles_deg) {
                if let Some(slot) = column.and_then(|j| measured.get_mut(j)) {
                    *slot = Some(streams.units.from_rad(deg.to_radians()));
                }
            }
            streams.rerun.pose(row.time_s, &[], &measured);
        }
        if let (false, Some((out, _))) = (text.is_empty(), &mut streams.file) {
            out.write_all(text.as_bytes())?;
            out.flush()?;
        }
        if last {
            return Ok(());
        }
        if !stop.load(Ordering::SeqCst) {
            std::thread::sleep(TRUTH_PASS);
        } else {
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
    }
}

/// Appends one truth row, `time_s,<angle>,...`, the base's pose when
/// given (`base_x_m,base_y_m,base_theta_deg`) and its newline, to `text`.
fn push_row(text: &mut String, time_s: f64, angles_deg: &[f64], base: Option<Odometry>) {
    use std::fmt::Write as _;
    // Writing to a String cannot fail.
    let _ = write!(text, "{time_s:.3}");
    for a in angles_deg {
        let _ = write!(text, ",{a:.3}");
    }
    if let Some(pose) = base {
        for (_, v) in pose_figures(&pose) {
            let _ = write!(text, ",{v:.5}");
        }
    }
    text.push('\n');
}

/// The servos to serve and the baud rate to serve them at
/// ([`SimRobotBuilder::served`]): a bus that is not there, or an ID on two
/// served buses, is the user's input error.
fn servos_of(
    builder: &SimRobotBuilder<'_>,
    only: Option<&str>,
) -> anyhow::Result<(u32, Vec<SimServo>)> {
    builder.served(only).map_err(|e| match e {
        SimRobotError::SharedId { .. } => {
            crate::shared::exit::input(format!("{e}; serve one bus at a time with --bus"))
        }
        SimRobotError::NoBus { .. } | SimRobotError::NoSuchBus { .. } => {
            crate::shared::exit::input(e.to_string())
        }
        other => other.into(),
    })
}
