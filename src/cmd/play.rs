//! `servobus play`: a choreography on the simulated robot or on real servos.
//!
//! Everything is checked before anything moves: both files, every keyframe
//! against the joint limits, the path against the velocity, acceleration and
//! jerk limits, and the rate against every bus's budget. Then the plan is
//! printed in one short block, the run starts (on real servos, with a slow
//! approach from wherever the joints are to the first keyframe), a progress
//! line follows it, and a report closes it.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use anyhow::Context;
use crossbeam_channel::RecvTimeoutError;
use servobus_driver::{Bus, SerialTransport, SystemClock, Transport};
use servobus_runtime::config::{
    load_motion_calibrated, plan_motion, Motion, RateRemedy, Robot, Units,
};
use servobus_runtime::rt::RtOptions;
use servobus_runtime::{
    bus_settings, spawn, spawn_virtual, Command, FaultPolicy, Finish, Lead, Report, RunOptions,
    Runner, Telemetry,
};
use servobus_sim::PtyServer;
use servobus_trajectory::Trajectory;

use crate::record::{read_recording, CsvLog, PlotData};

/// Arguments of `servobus play`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The motion file (or a built-in motion's name, `servobus list`), or a
    /// recorded path (.csv: a `play --log` file or `time_s,<joint>...` in
    /// degrees; needs --robot).
    #[arg(value_parser = super::motion_arg)]
    pub motion: PathBuf,
    /// Robot file or built-in name (default: the one the motion file names).
    #[arg(long, value_parser = super::robot_arg)]
    pub robot: Option<PathBuf>,
    /// Serial port of real servos, for the robot's first bus (default: the
    /// robot file's ports; without any, the built-in simulator).
    #[arg(long)]
    pub port: Option<String>,
    /// Calibration file of the physical robot (default: the robot file's
    /// `calibration:`).
    #[arg(long)]
    pub calibration: Option<PathBuf>,
    /// Control rate in Hz (default: the motion's, else the robot's).
    #[arg(long)]
    pub rate: Option<f64>,
    /// Allow a rate above the maximum by reading servos round-robin (a
    /// subset each cycle), as `round_robin: true` on every bus.
    #[arg(long)]
    pub round_robin: bool,
    /// Run the simulator in virtual time, as fast as the CPU allows.
    #[arg(long, conflicts_with = "port")]
    pub fast: bool,
    /// Print the report as one JSON object (and no progress on stdout).
    #[arg(long)]
    pub json: bool,
    /// Write one CSV row per cycle and joint.
    #[arg(long)]
    pub log: Option<PathBuf>,
    /// Draw planned vs measured positions and the tracking error: SVG
    /// (.svg) or PNG (.png); any other extension is refused before moving.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Wait for replies by polling the port without blocking, on every bus
    /// (as `busy_poll: true` in the robot file): saves the kernel's wake-up
    /// latency on each reply at the cost of a busy core per bus.
    #[arg(long, conflicts_with = "fast")]
    pub busy_poll: bool,
    /// Pin the control thread of the first bus to this core (the next bus
    /// to the next core, and so on).
    #[arg(long)]
    pub core: Option<usize>,
    /// Run the control threads under SCHED_FIFO at this priority (1..=99);
    /// where not permitted, a warning and normal scheduling.
    #[arg(long, value_parser = clap::value_parser!(i32).range(1..=99))]
    pub fifo: Option<i32>,
    /// Show the live servo view of `servobus monitor` while playing, from
    /// the run's telemetry (no extra bus traffic).
    #[arg(long, conflicts_with_all = ["json", "log", "plot"])]
    pub monitor: bool,
    /// Start the simulated joints at these angles instead of their rest
    /// positions (robot units, robot joint order, comma-separated, e.g.
    /// `--sim-pose=30,-60,70,10,40,50`): the run approaches the first
    /// keyframe from there, as on real servos.
    #[arg(
        long,
        value_delimiter = ',',
        allow_negative_numbers = true,
        conflicts_with = "port"
    )]
    pub sim_pose: Option<Vec<f64>>,
}

/// Where the run happens.
enum Backend {
    /// Simulated buses in virtual time.
    Fast,
    /// The simulator on pseudo-terminals, in wall-clock time.
    Simulated,
    /// Real servos: one port per bus.
    Hardware(Vec<String>),
}

/// Runs `servobus play`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    check_outputs(&args)?;
    let (motion, robot, trajectory, recording, rate_hz) = load(&args)?;
    let backend = backend(&args, &robot)?;
    let pose = sim_pose(&args, &robot, &backend)?;
    if !args.json {
        print_plan(&motion, &robot, &trajectory, rate_hz, &backend)?;
        if let Some(r) = &recording {
            println!("  {}", r.describe(motion.units));
        }
    }
    // Outputs are created before anything moves: a path that cannot be
    // written fails now, not after the run.
    let log = match &args.log {
        Some(path) => Some(CsvLog::create(
            path,
            names_of(&robot),
            &motion.units.to_string(),
        )?),
        None => None,
    };

    let options = RunOptions {
        rate_hz: Some(rate_hz),
        units: Some(motion.units),
        settle: SETTLE,
        // The simulated joints start at rest; real ones wherever they are.
        // Both approach the first keyframe slowly (skipped when already
        // there).
        approach: Some(APPROACH),
        lead: robot.lead.map_or_else(Lead::default, Lead::Fixed),
        rt: RtOptions {
            core: args.core,
            fifo_priority: args.fifo,
        },
        faults: fault_policy(&backend, rate_hz),
        ..RunOptions::default()
    };

    let names: Vec<String> = robot.joints().map(|j| j.name.clone()).collect();
    let units = motion.units;
    let duration = trajectory.duration();
    let keyframe_times: Vec<f64> = trajectory.segments().iter().map(|s| s.end).collect();
    let mut start = vec![servobus_trajectory::JointState::default(); trajectory.joints()];
    trajectory.sample(0.0, &mut start);
    let start: Vec<f64> = start.iter().map(|s| s.position).collect();
    let mut servers = Vec::new();
    let stop_servers = Arc::new(AtomicBool::new(false));
    let runner = match &backend {
        Backend::Fast => {
            let buses = servobus_runtime::sim::SimRobot::builder(&robot)
                .pose(&pose)
                .build()?
                .driver_buses();
            spawn_virtual(&robot, trajectory, buses, options)?
        }
        Backend::Simulated => {
            let clock = SystemClock::new();
            let mut buses = Vec::new();
            let sim = servobus_runtime::sim::SimRobot::builder(&robot).pose(&pose);
            for bus in &robot.buses {
                let mut server = PtyServer::open(bus.baud, sim.servos(bus)?)
                    .with_context(|| format!("bus `{}`: cannot start the simulator", bus.name))?;
                let path = server.path().to_string_lossy().into_owned();
                let flag = Arc::clone(&stop_servers);
                servers.push(std::thread::spawn(move || server.serve(&flag)));
                let mut transport = SerialTransport::open(&path, bus.baud, clock)
                    .with_context(|| format!("cannot open the simulator's pty {path}"))?;
                transport.set_busy_poll(bus.busy_poll || args.busy_poll);
                let transport: Box<dyn Transport + Send> = Box::new(transport);
                // A pty on a busy machine wakes late now and then: allow
                // for it in the reply deadlines.
                let settings = bus_settings(bus)
                    .with_latency(bus.latency.max(servobus_timing::Link::PTY_LATENCY));
                buses.push(Bus::new(transport, clock, settings));
            }
            spawn(&robot, trajectory, buses, options)?
        }
        Backend::Hardware(ports) => {
            let clock = SystemClock::new();
            let mut buses = Vec::new();
            let mut ptys = 0;
            for (bus, port) in robot.buses.iter().zip(ports) {
                let mut transport = SerialTransport::open(port, bus.baud, clock)
                    .with_context(|| format!("bus `{}`: cannot open {port}", bus.name))?;
                transport.set_busy_poll(bus.busy_poll || args.busy_poll);
                if let Some(warning) = transport.ftdi_latency().and_then(|f| f.warning()) {
                    eprintln!("warning: {warning}");
                }
                let mut settings = bus_settings(bus);
                if transport.is_pty() {
                    // A simulator served on a pty (`servobus sim`) answers
                    // from a process that can wait for the CPU, as the
                    // built-in one does: the same allowances.
                    settings =
                        settings.with_latency(bus.latency.max(servobus_timing::Link::PTY_LATENCY));
                    ptys += 1;
                }
                let transport: Box<dyn Transport + Send> = Box::new(transport);
                buses.push(Bus::new(transport, clock, settings));
            }
            super::calibrate::check_buses(&robot, &mut buses, ports)?;
            let faults = if ptys == buses.len() {
                fault_policy(&Backend::Simulated, rate_hz)
            } else {
                options.faults
            };
            spawn(&robot, trajectory, buses, RunOptions { faults, ..options })?
        }
    };

    let interrupts = install_ctrl_c(&runner)?;
    let shown = Shown {
        names: names.clone(),
        bus_of: robot
            .buses
            .iter()
            .enumerate()
            .flat_map(|(b, bus)| bus.joints.iter().map(move |_| b))
            .collect(),
        keyframes: keyframe_times,
        start,
        limits: servobus_runtime::config::joint_limits(&robot),
        settle: SETTLE.as_secs_f64(),
    };
    let outcome = if args.monitor {
        super::monitor::watch_run(&runner, &robot, units, rate_hz).map(|()| (None, None))
    } else {
        follow(&runner, &args, log, &shown, units, duration, &interrupts)
    };
    let report = runner.join();
    stop_servers.store(true, Ordering::SeqCst);
    join_servers(servers);
    let (log, plot) = outcome?;
    let report = report?;

    if let Some(log) = log {
        log.finish()?;
    }
    if let (Some(plot), Some(path)) = (plot, &args.plot) {
        let title = format!(
            "{} on {}: planned vs measured",
            file_name(&motion.path),
            robot.name
        );
        plot.draw(path, &title, &units.to_string())?;
    }
    if args.json {
        let mut value = serde_json::to_value(&report)?;
        if let (Some(r), Some(obj)) = (&recording, value.as_object_mut()) {
            obj.insert("recording".into(), r.json(motion.units));
        }
        println!("{}", serde_json::to_string_pretty(&value)?);
    } else {
        print_report(&report, robot.lead.is_none());
        if let Some(r) = &recording {
            println!("  {}", r.describe(motion.units));
        }
        if let Some(path) = &args.log {
            println!("log: {}", path.display());
        }
        if let Some(path) = &args.plot {
            println!("plot: {}", path.display());
        }
    }
    Ok(match report.finish {
        Finish::Completed | Finish::Stopped => ExitCode::SUCCESS,
        _ => ExitCode::FAILURE,
    })
}

fn names_of(robot: &Robot) -> Vec<String> {
    robot.joints().map(|j| j.name.clone()).collect()
}

/// Plot formats `--plot` writes, by file extension.
const PLOT_FORMATS: [&str; 2] = ["svg", "png"];

/// Fails at once on an output that could not be written after the run: a
/// plot format not supported, or a directory that does not exist.
fn check_outputs(args: &Args) -> anyhow::Result<()> {
    if let Some(path) = &args.plot {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        if !PLOT_FORMATS.contains(&ext.as_str()) {
            return Err(super::exit::input(format!(
                "--plot {}: plots are written as SVG (.svg) or PNG (.png); give one of those",
                path.display()
            )));
        }
    }
    for (flag, path) in [("--plot", &args.plot), ("--log", &args.log)] {
        let Some(path) = path else { continue };
        let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
        if let Some(dir) = dir {
            if !dir.is_dir() {
                return Err(super::exit::input(format!(
                    "{flag} {}: the directory {} does not exist; nothing was moved",
                    path.display(),
                    dir.display()
                )));
            }
        }
        std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .with_context(|| {
                format!(
                    "{flag} {}: cannot write there; nothing was moved",
                    path.display()
                )
            })?;
    }
    Ok(())
}

/// A recording played back: what the filter did to it.
struct RecordingInfo {
    samples: usize,
    span_s: f64,
    names: Vec<String>,
    max_rad: Vec<f64>,
    rms_rad: Vec<f64>,
    missing: Vec<String>,
}

impl RecordingInfo {
    /// The worst joint's departure, in one line.
    fn describe(&self, u: Units) -> String {
        let worst = (0..self.max_rad.len())
            .max_by(|&a, &b| self.max_rad[a].total_cmp(&self.max_rad[b]))
            .unwrap_or(0);
        let mut text = format!(
            "recording: {} samples over {:.2} s, filtered to the limits; departs from it by at \
             most {:.2} {u} ({}), rms {:.2} {u}",
            self.samples,
            self.span_s,
            u.from_rad(self.max_rad.get(worst).copied().unwrap_or(0.0)),
            self.names.get(worst).map_or("?", String::as_str),
            u.from_rad(self.rms_rad.get(worst).copied().unwrap_or(0.0)),
        );
        if !self.missing.is_empty() {
            text += &format!("; not recorded, held at rest: {}", self.missing.join(", "));
        }
        text
    }

    fn json(&self, u: Units) -> serde_json::Value {
        let joints: Vec<serde_json::Value> = self
            .names
            .iter()
            .enumerate()
            .map(|(j, name)| {
                serde_json::json!({
                    "name": name,
                    "max_departure": u.from_rad(self.max_rad[j]),
                    "rms_departure": u.from_rad(self.rms_rad[j]),
                })
            })
            .collect();
        serde_json::json!({
            "samples": self.samples,
            "span_s": self.span_s,
            "joints": joints,
        })
    }
}

type Loaded = (Motion, Robot, Trajectory, Option<RecordingInfo>, f64);

/// The motion file planned, or the recording (`.csv`) filtered, with the
/// control rate; every limit and the buses' budgets checked.
fn load(args: &Args) -> anyhow::Result<Loaded> {
    let recorded = args
        .motion
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let (motion, mut robot) = if recorded {
        let Some(robot_path) = &args.robot else {
            return Err(super::exit::input(format!(
                "{}: a recorded path names no robot; give --robot FILE",
                args.motion.display()
            )));
        };
        let robot = servobus_runtime::config::load_robot_calibrated(
            robot_path,
            args.calibration.as_deref(),
        )?;
        (recording_motion(&args.motion, &robot), robot)
    } else {
        load_motion_calibrated(
            &args.motion,
            args.robot.as_deref(),
            args.calibration.as_deref(),
        )?
    };
    let rate_hz = match args.rate {
        Some(rate) if !(rate.is_finite() && rate > 0.0) => {
            return Err(super::exit::input(format!(
                "--rate {rate}: give a positive rate in Hz"
            )))
        }
        Some(rate) => rate,
        None => motion.rate_hz(&robot),
    };
    for bus in &mut robot.buses {
        bus.round_robin |= args.round_robin;
        if let Err(why) = bus.check_rate(rate_hz) {
            let why = why.with_remedy(RateRemedy::Flag);
            return Err(super::exit::input(format!("bus `{}`: {why}", bus.name)));
        }
    }
    if !recorded {
        let trajectory = plan_motion(&motion, &robot)?;
        return Ok((motion, robot, trajectory, None, rate_hz));
    }
    let rec = read_recording(&args.motion, &robot)?;
    let limits = servobus_runtime::config::joint_limits(&robot);
    let tracked = servobus_trajectory::track(&limits, &rec.times, &rec.samples, 1.0 / rate_hz)
        .map_err(|e| {
            anyhow::anyhow!("{}: cannot play this recording: {e}", args.motion.display())
        })?;
    let info = RecordingInfo {
        samples: rec.times.len(),
        span_s: rec.times[rec.times.len() - 1] - rec.times[0],
        names: names_of(&robot),
        max_rad: tracked.max_deviation,
        rms_rad: tracked.rms_deviation,
        missing: rec.missing,
    };
    Ok((motion, robot, tracked.trajectory, Some(info), rate_hz))
}

/// A stand-in motion for a recording (its name, the robot's joints), so the
/// plan and report read the same as for a motion file.
fn recording_motion(path: &Path, robot: &Robot) -> Motion {
    Motion {
        path: path.to_owned(),
        robot_path: robot.path.clone(),
        units: Units::Deg,
        rate_hz: None,
        joints: names_of(robot),
        keyframes: Vec::new(),
        repeat: 1,
        on_limit: Default::default(),
        interpolation: Default::default(),
    }
}

/// How long the final position is held (and tracked) after the path.
const SETTLE: Duration = Duration::from_millis(300);

/// The fraction of the limits the runtime's approach moves at (its
/// `RunOptions::approach`), and the distance under which it is skipped
/// (half a degree, as the runtime's).
const APPROACH: f64 = 0.25;
const APPROACH_SKIP_RAD: f64 = 0.5 * std::f64::consts::PI / 180.0;

/// What the live view and the plot show besides the telemetry.
struct Shown {
    names: Vec<String>,
    bus_of: Vec<usize>,
    /// Path times of the keyframes.
    keyframes: Vec<f64>,
    /// The path's first position per joint, rad.
    start: Vec<f64>,
    limits: Vec<servobus_trajectory::JointLimits>,
    settle: f64,
}

impl Shown {
    /// How long the approach from `present` (rad) to the path's start
    /// takes: the same jerk-limited move at the same fraction of the
    /// limits as the runtime plans, or 0 when it is skipped.
    fn approach_s(&self, present: &[f64]) -> f64 {
        let far = present
            .iter()
            .zip(&self.start)
            .any(|(p, q)| (p - q).abs() > APPROACH_SKIP_RAD);
        if !far {
            return 0.0;
        }
        let lim: Vec<_> = self
            .limits
            .iter()
            .map(|l| {
                servobus_trajectory::JointLimits::new(
                    l.max_velocity * APPROACH,
                    l.max_acceleration * APPROACH,
                    l.max_jerk.map(|j| j * APPROACH),
                )
            })
            .collect();
        let from: Vec<_> = present
            .iter()
            .map(|&p| servobus_trajectory::JointState::at_rest(p))
            .collect();
        servobus_trajectory::retarget(&lim, &from, &self.start).map_or(0.0, |t| t.duration())
    }
}

/// How long the simulator on a pty may stay silent before a servo counts as
/// missing. Its replies come from a thread of this process: when the host
/// takes the CPU away for a few milliseconds (shared and virtual machines
/// do), several replies in a row arrive late although no servo is gone.
const PTY_SILENCE: Duration = Duration::from_millis(60);

/// The fault policy of a run: the defaults (a servo silent for 3 reads is
/// missing), except on the simulator in wall-clock time, where a silence
/// must also last [`PTY_SILENCE`].
fn fault_policy(backend: &Backend, rate_hz: f64) -> FaultPolicy {
    let defaults = FaultPolicy::default();
    match backend {
        Backend::Simulated => {
            let cycles = (PTY_SILENCE.as_secs_f64() * rate_hz).ceil() as u32;
            FaultPolicy {
                missing_cycles: defaults.missing_cycles.max(cycles),
                ..defaults
            }
        }
        Backend::Fast | Backend::Hardware(_) => defaults,
    }
}

/// Where the simulated joints start (robot units, robot joint order):
/// `--sim-pose`, checked against the robot, else the rest positions.
fn sim_pose(args: &Args, robot: &Robot, backend: &Backend) -> anyhow::Result<Vec<f64>> {
    let Some(pose) = &args.sim_pose else {
        return Ok(robot.joints().map(|j| j.rest()).collect());
    };
    if let Backend::Hardware(_) = backend {
        return Err(super::exit::input(
            "--sim-pose sets where the simulator starts; real servos start where they are",
        ));
    }
    if pose.len() != robot.joint_count() {
        return Err(super::exit::input(format!(
            "--sim-pose has {} angles; {} has {} joints",
            pose.len(),
            robot.name,
            robot.joint_count()
        )));
    }
    for (j, &a) in robot.joints().zip(pose) {
        if !(j.min..=j.max).contains(&a) {
            return Err(super::exit::input(format!(
                "--sim-pose: {} = {a} is outside its limits {}..{}",
                j.name, j.min, j.max
            )));
        }
    }
    Ok(pose.clone())
}

fn backend(args: &Args, robot: &Robot) -> anyhow::Result<Backend> {
    if args.fast {
        return Ok(Backend::Fast);
    }
    let mut ports: Vec<Option<String>> = robot.buses.iter().map(|b| b.port.clone()).collect();
    if let (Some(port), Some(first)) = (&args.port, ports.first_mut()) {
        *first = Some(port.clone());
    }
    if ports.iter().all(Option::is_none) {
        return Ok(Backend::Simulated);
    }
    let mut out = Vec::new();
    for (bus, port) in robot.buses.iter().zip(ports) {
        match port {
            Some(p) => out.push(p),
            None => {
                return Err(super::exit::input(format!(
                    "bus `{}` of {} has no port: give every bus a `port:` in the robot file \
                 (--port sets only the first bus's)",
                    bus.name,
                    robot.path.display()
                )))
            }
        }
    }
    Ok(Backend::Hardware(out))
}

fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    )
}

fn print_plan(
    motion: &Motion,
    robot: &Robot,
    trajectory: &Trajectory,
    rate_hz: f64,
    backend: &Backend,
) -> anyhow::Result<()> {
    let on = match backend {
        Backend::Fast => "the simulator, virtual time".to_string(),
        Backend::Simulated => "the simulator, real time".to_string(),
        Backend::Hardware(ports) => format!("servos on {}", ports.join(", ")),
    };
    println!(
        "{} on {} ({} joints, {} bus{}) via {on}",
        file_name(&motion.path),
        robot.name,
        robot.joint_count(),
        robot.buses.len(),
        if robot.buses.len() == 1 { "" } else { "es" },
    );
    println!(
        "  path {:.2} s, {} keyframes x {}, at {rate_hz} Hz",
        trajectory.duration(),
        motion.keyframes.len(),
        motion.repeat
    );
    for bus in &robot.buses {
        let plan = bus.plan(rate_hz)?;
        let every = if plan.read_every() > 1 {
            format!(", each servo read every {} cycles", plan.read_every())
        } else {
            String::new()
        };
        println!(
            "  bus {}: {} servos at {} baud, {} B and {:.0} us per cycle, {:.1} % of the period \
             (max {:.0} Hz){every}",
            bus.name,
            plan.servos(),
            bus.baud,
            plan.bytes_per_cycle(),
            plan.cycle_time_us(),
            100.0 * plan.utilisation(),
            plan.fastest_rate_hz(),
        );
    }
    Ok(())
}

/// Ctrl-C once: a jerk-limited stop, then hold and report. Twice: torque off.
fn install_ctrl_c(runner: &Runner) -> anyhow::Result<Arc<AtomicU32>> {
    let count = Arc::new(AtomicU32::new(0));
    let seen = Arc::clone(&count);
    let commands = runner.commands();
    let installed = ctrlc::set_handler(move || {
        let n = seen.fetch_add(1, Ordering::SeqCst);
        let command = if n == 0 {
            eprintln!("\nstopping (jerk-limited), then holding; Ctrl-C again turns the torque off");
            Command::Stop
        } else {
            eprintln!("\ntorque off");
            Command::TorqueOff
        };
        // The run may have ended already; nothing else to do then.
        let _ = commands.try_send(command);
    });
    if let Err(e) = installed {
        // Tests and embedders may have a handler already; playing still works.
        eprintln!("warning: Ctrl-C handling unavailable ({e})");
    }
    Ok(count)
}

/// Reads the telemetry until the run ends: progress, log, plot series.
#[allow(clippy::too_many_arguments)] // the run, its outputs and what they show
fn follow(
    runner: &Runner,
    args: &Args,
    mut log: Option<CsvLog>,
    shown: &Shown,
    units: Units,
    duration: f64,
    _interrupts: &AtomicU32,
) -> anyhow::Result<(Option<CsvLog>, Option<PlotData>)> {
    let mut plot = args
        .plot
        .as_ref()
        .map(|_| PlotData::new(shown.names.clone(), shown.bus_of.clone()));
    // The joints' positions at the first cycle (rad), until all are known:
    // they give the approach's duration.
    let mut present: Vec<Option<f64>> = vec![None; shown.names.len()];
    let mut announced = false;
    let mut progress = Progress::new(args.json, duration, &units.to_string());
    let telemetry = runner.telemetry();
    loop {
        match telemetry.recv_timeout(Duration::from_millis(100)) {
            Ok(Telemetry::Cycle(sample)) => {
                if !announced {
                    for j in sample.joints() {
                        if let Some(slot) = present.get_mut(j.joint) {
                            slot.get_or_insert(units.to_rad(j.measured.unwrap_or(j.planned)));
                        }
                    }
                    if present.iter().all(Option::is_some) {
                        announced = true;
                        let now: Vec<f64> = present.iter().map(|p| p.unwrap_or(0.0)).collect();
                        let approach = shown.approach_s(&now);
                        if approach > 0.0 {
                            progress
                                .message(&format!("moving to the first keyframe, {approach:.1} s"));
                        }
                        progress.set_total(approach + duration + shown.settle);
                        if let Some(plot) = &mut plot {
                            plot.mark_keyframes(shown.keyframes.iter().map(|t| t + approach));
                        }
                    }
                }
                if let Some(log) = &mut log {
                    log.record(&sample)?;
                }
                if let Some(plot) = &mut plot {
                    plot.record(&sample);
                }
                progress.cycle(&sample);
            }
            Ok(Telemetry::Fault(fault)) => progress.message(&format!("fault: {fault}")),
            Ok(Telemetry::Finished(_)) => {}
            Ok(_) => {}
            Err(RecvTimeoutError::Timeout) => {
                if runner.is_finished() && telemetry.is_empty() {
                    break;
                }
            }
            Err(RecvTimeoutError::Disconnected) => break,
        }
    }
    progress.finish();
    Ok((log, plot))
}

/// The live progress: a bar on a terminal, a line a second otherwise.
struct Progress {
    bar: Option<indicatif::ProgressBar>,
    plain: bool,
    units: String,
    duration: f64,
    worst: f64,
    first: Option<(u64, f64)>,
    last: (u64, f64),
    last_line: Instant,
}

impl Progress {
    fn new(json: bool, duration: f64, units: &str) -> Self {
        let terminal = std::io::stdout().is_terminal();
        let bar = (!json && terminal).then(|| {
            let bar = indicatif::ProgressBar::new((duration * 1000.0).max(1.0) as u64);
            let style = indicatif::ProgressStyle::with_template("{spinner} [{bar:40}] {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
                .progress_chars("=> ");
            bar.set_style(style);
            bar
        });
        Progress {
            bar,
            plain: !json && !terminal,
            units: units.to_string(),
            duration,
            worst: 0.0,
            first: None,
            last: (0, 0.0),
            last_line: Instant::now(),
        }
    }

    fn cycle(&mut self, sample: &servobus_runtime::CycleSample) {
        for j in sample.joints() {
            if j.measured.is_some() && !j.stale {
                self.worst = self.worst.max(j.error.abs());
            }
        }
        if sample.bus != 0 {
            return;
        }
        let first = *self.first.get_or_insert((sample.cycle, sample.time_s));
        self.last = (sample.cycle, sample.time_s);
        let span = self.last.1 - first.1;
        let rate = if span > 0.0 {
            (self.last.0 - first.0) as f64 / span
        } else {
            0.0
        };
        let msg = format!(
            "{:.1} / {:.1} s  {:.1} Hz  worst error {:.2} {}",
            sample.time_s, self.duration, rate, self.worst, self.units
        );
        if let Some(bar) = &self.bar {
            bar.set_length((self.duration.max(sample.time_s) * 1000.0) as u64);
            bar.set_position((sample.time_s * 1000.0) as u64);
            bar.set_message(msg);
        } else if self.plain && self.last_line.elapsed() >= Duration::from_secs(1) {
            self.last_line = Instant::now();
            println!("{msg}");
        }
    }

    /// The run's whole length: approach, path and settling.
    fn set_total(&mut self, total_s: f64) {
        self.duration = total_s;
    }

    fn message(&self, text: &str) {
        match &self.bar {
            Some(bar) => bar.println(text),
            None => eprintln!("{text}"),
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

fn join_servers(servers: Vec<JoinHandle<Result<(), servobus_sim::PtyError>>>) {
    for server in servers {
        match server.join() {
            Ok(Ok(())) => {}
            Ok(Err(e)) => eprintln!("warning: simulator: {e}"),
            Err(_) => eprintln!("warning: a simulator thread panicked"),
        }
    }
}

/// Prints the end-of-run report; `identified`: the lead was found while
/// playing rather than set in the robot file.
fn print_report(r: &Report, identified: bool) {
    println!(
        "{}: {} cycles in {:.2} s, {:.1} Hz achieved of {:.1} Hz requested",
        match r.finish {
            Finish::Completed => "completed",
            Finish::Stopped => "stopped",
            Finish::TorqueOff => "torque off",
            Finish::Fault => "FAULT",
            _ => "ended",
        },
        r.cycles,
        r.duration_s,
        r.achieved_rate_hz,
        r.planned_rate_hz
    );
    println!(
        "  period error us: p50 {:.0}  p99 {:.0}  max {:.0};  overruns {}  drift {:.0} us",
        r.period_error_us.p50, r.period_error_us.p99, r.period_error_us.max, r.overruns, r.drift_us
    );
    println!(
        "  bus utilisation {:.1} %;  timeouts {}  retries {}  missed replies {}  clamps {}  \
         telemetry dropped {}",
        100.0 * r.utilisation,
        r.timeouts,
        r.retries,
        r.missed_replies,
        r.clamps,
        r.telemetry_dropped
    );
    for b in &r.buses {
        let how = if b.latency_learned {
            format!(
                "learned (auto; {} PINGs in {:.1} ms at start-up)",
                b.startup_probes, b.startup_probe_ms
            )
        } else {
            "as the robot file gives it".to_owned()
        };
        println!(
            "  bus {} link: latency mean {:.0} us, p99 {:.0} us, {how}; reply deadline {:.0} us",
            b.name, b.latency_us, b.latency_p99_us, b.reply_deadline_us
        );
    }
    if identified && r.lead_ms > 0.0 {
        println!(
            "  lag compensation lead {:.1} ms, identified while moving \
             (`lead_ms: {:.0}` in the robot file applies it from the first cycle)",
            r.lead_ms, r.lead_ms
        );
    } else {
        println!("  lag compensation lead {:.1} ms", r.lead_ms);
    }
    // The name column fits the longest joint name.
    let w = r.joints.iter().map(|j| j.name.len()).fold(16, usize::max);
    println!(
        "  {:<w$} {:>10} {:>10}   tracking error ({})",
        "joint", "rms", "max", r.units
    );
    for j in &r.joints {
        println!(
            "  {:<w$} {:>10.3} {:>10.3}",
            j.name, j.rms_error, j.max_error
        );
    }
    if let Some(fault) = &r.fault {
        println!("  fault: {fault}");
    }
    for w in &r.warnings {
        println!("  warning: {w}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_wall_clock_simulator_tolerates_a_longer_silence() {
        assert_eq!(fault_policy(&Backend::Fast, 200.0), FaultPolicy::default());
        let hw = Backend::Hardware(vec!["/dev/ttyACM0".into()]);
        assert_eq!(fault_policy(&hw, 200.0), FaultPolicy::default());
        assert_eq!(fault_policy(&Backend::Simulated, 200.0).missing_cycles, 12);
        assert_eq!(fault_policy(&Backend::Simulated, 20.0).missing_cycles, 3);
    }
}
