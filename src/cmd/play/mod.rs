//! `servobus play`: a choreography on the simulated robot or on real servos.
//!
//! Everything is checked before anything moves: both files, every keyframe
//! against the joint limits, the path against the velocity, acceleration and
//! jerk limits, and the rate against every bus's budget. Then the plan is
//! printed in one short block, the run starts (on real servos, with a slow
//! approach from wherever the joints are to the first keyframe), a progress
//! line follows it, and a report closes it.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use crossbeam_channel::RecvTimeoutError;
use servobus_config::{
    check_motion_length, limits, load_motion_calibrated, plan_motion, Motion, Robot, Units,
};
use servobus_robot::Trajectory;
use servobus_robot::{Command, CommandSender, Lead, RtOptions, Run, RunOptions, Telemetry};

use crate::record::{read_recording, CsvLog, PlotData};
use crate::shared::ports::{every_port, Ports};

// `run` below is the order of events; each step's details live by concern:
// reading the inputs, where the run happens, what is shown while it runs
// and after.
mod load;
mod report;
mod setup;
mod view;

use crate::shared::install_ctrl_c;
use crate::shared::write_report;
use load::{check_outputs, load};
use report::{print_plan, report_text, Outputs};
use setup::{backend, run_options, sim_pose, start};
use view::{follow, Followed, Shown, APPROACH, SETTLE};

use crate::shared::out::outln;

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
    /// The port of real servos and their calibration.
    #[command(flatten)]
    pub hardware: super::HardwareArgs,
    /// Control rate in Hz (default: the motion's, else the robot's).
    #[arg(long, value_parser = super::rate_arg)]
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
    /// the run's telemetry (no extra bus traffic). Needs a terminal: refused
    /// (exit 2) before anything moves without one.
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
    /// Tell every robot serving in this Zenoh group (`servobus serve
    /// --group NAME`) to play the motion together, instead of playing it
    /// here.
    #[cfg(feature = "zenoh")]
    #[arg(long, value_name = "NAME")]
    pub zenoh_group: Option<String>,
    /// With --zenoh-group: when the robots start, from now (`2s`, `500ms`).
    #[cfg(feature = "zenoh")]
    #[arg(long, default_value = "2s", requires = "zenoh_group", value_parser = crate::shared::args::duration_arg)]
    pub start_in: std::time::Duration,
    /// With --zenoh-group: a robot's endpoint to connect to (repeatable),
    /// e.g. tcp/127.0.0.1:7447.
    #[cfg(feature = "zenoh")]
    #[arg(long, value_name = "ENDPOINT", requires = "zenoh_group")]
    pub connect: Vec<String>,
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
/// (`--zenoh-group` is the group's play, which the dispatcher hands to
/// `serve`'s conductor instead.)
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let Prepared {
        motion,
        robot,
        trajectory,
        recording,
        rate_hz,
        backend,
        pose,
        log,
    } = prepare(&args)?;
    let units = motion.units;
    let duration = trajectory.duration();
    // The first keyframe is the path's start; each segment ends at the next.
    let keyframes: Vec<f64> = std::iter::once(0.0)
        .chain(trajectory.segments().iter().map(|s| s.end))
        .collect();
    let options = run_options(&args, &robot, units, rate_hz);
    let runner = start(&backend, &robot, &pose, trajectory, options, rate_hz)?;

    install_ctrl_c(runner.commands());
    let shown = Shown {
        names: names_of(&robot),
        bus_of: robot
            .buses
            .iter()
            .flat_map(|bus| bus.joints.iter().map(|_| bus.name.clone()))
            .collect(),
        keyframes,
        approach: runner.approach().as_secs_f64(),
        settle: SETTLE.as_secs_f64(),
        geometry: robot.geometry(),
        recording: recording.as_ref().map(|r| r.series.as_slice()),
    };
    let outcome = if args.monitor {
        crate::shared::screen::watch_run(&runner, &robot, units, rate_hz).map(|()| Followed {
            log: None,
            plot: None,
            stdout: None,
        })
    } else {
        follow(&runner, &args, log, &shown, units, duration)
    };
    let report = runner.join();
    let Followed { log, plot, stdout } = outcome?;
    // The run has moved: what it logged is kept, also when it ended in an
    // error (the error is said after the log is in place).
    let mut outputs = Outputs::default();
    outputs.finish_log(log);
    let report = match report {
        Ok(report) => report,
        Err(e) => {
            outputs.say_failed();
            return Err(e.into());
        }
    };
    if let (Some(plot), Some(path)) = (plot, &args.plot) {
        outputs.draw_plot(&plot, path, &motion, &robot);
    }
    let text = report_text(
        &args,
        &report,
        &motion,
        &robot,
        recording.as_ref(),
        &outputs,
    )?;
    outputs.print(&text, stdout)?;
    Ok(crate::shared::exit::of_finish(report.finish))
}

/// What is known and made before anything moves.
struct Prepared {
    motion: Motion,
    robot: Robot,
    trajectory: Trajectory,
    recording: Option<load::RecordingInfo>,
    rate_hz: f64,
    backend: Backend,
    /// Where the simulated joints start.
    pose: Vec<f64>,
    /// The log's temporary, with `--log`.
    log: Option<CsvLog>,
}

/// Checks everything before anything moves: the terminal `--monitor`
/// needs, the outputs, the inputs and where the run happens; prints the
/// plan and creates the log's temporary.
fn prepare(args: &Args) -> anyhow::Result<Prepared> {
    if args.monitor {
        // The live view needs a terminal: without one, refuse before
        // anything is opened or moved.
        crate::shared::screen::check_play_terminal()?;
    }
    check_outputs(args)?;
    let (motion, robot, trajectory, recording, rate_hz) = load(args)?;
    let backend = backend(args, &robot)?;
    let pose = sim_pose(args, &robot, &backend)?;
    if !args.json {
        // Stdout that cannot be written (closed, full) fails the command
        // here, before anything moves.
        print_plan(&motion, &robot, &trajectory, rate_hz, &backend)?;
        if let Some(r) = &recording {
            outln!("  {}", r.describe(motion.units))?;
        }
    }
    // The log's temporary is created before anything moves: a path that
    // cannot be written fails now, not after the run. A run refused from
    // here on drops it, and a log already at the path is untouched.
    let log = match &args.log {
        Some(path) => Some(CsvLog::create(
            path,
            names_of(&robot),
            motion.units,
            robot.geometry(),
        )?),
        None => None,
    };
    Ok(Prepared {
        motion,
        robot,
        trajectory,
        recording,
        rate_hz,
        backend,
        pose,
        log,
    })
}

/// The robot's joint names, in its joint order.
fn names_of(robot: &Robot) -> Vec<String> {
    robot.joints().map(|j| j.name.clone()).collect()
}
