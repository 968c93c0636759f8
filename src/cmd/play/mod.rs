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
use report::{file_name, print_plan};
use setup::{backend, check_measured_rates, sim_pose};
use view::{follow, Followed, Shown, APPROACH, SETTLE};

use crate::shared::out::{err, out, outln};

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
    if args.monitor {
        // The live view needs a terminal: without one, refuse before
        // anything is opened or moved.
        crate::shared::screen::check_play_terminal()?;
    }
    check_outputs(&args)?;
    let (motion, robot, trajectory, recording, rate_hz) = load(&args)?;
    let backend = backend(&args, &robot)?;
    let pose = sim_pose(&args, &robot, &backend)?;
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
        ..RunOptions::default()
    };

    let names: Vec<String> = robot.joints().map(|j| j.name.clone()).collect();
    let units = motion.units;
    let duration = trajectory.duration();
    // The first keyframe is the path's start; each segment ends at the next.
    let keyframe_times: Vec<f64> = std::iter::once(0.0)
        .chain(trajectory.segments().iter().map(|s| s.end))
        .collect();
    let runner = match &backend {
        // The built-in simulator in this process: in virtual time, or
        // paced by the wall clock with no pty between the run and its
        // servos.
        Backend::Fast | Backend::Simulated => {
            let target = if matches!(backend, Backend::Fast) {
                servobus_robot::Target::VirtualSimulator
            } else {
                servobus_robot::Target::Simulator
            };
            servobus_robot::Robot::from(robot.clone())
                .connect_at(target, &pose)?
                .play(trajectory, options)?
        }
        Backend::Hardware(ports) => {
            let mut connection = crate::shared::ports::connect(
                &robot,
                servobus_robot::Target::Ports(ports.to_vec()),
            )?;
            check_measured_rates(&mut connection, ports, rate_hz)?;
            connection.play(trajectory, options)?
        }
    };

    install_ctrl_c(runner.commands());
    let shown = Shown {
        names: names.clone(),
        bus_of: robot
            .buses
            .iter()
            .flat_map(|bus| bus.joints.iter().map(|_| bus.name.clone()))
            .collect(),
        keyframes: keyframe_times,
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
    let mut failed_outputs = Vec::new();
    let mut log_written = false;
    if let Some(log) = log {
        match log.finish() {
            Ok(()) => log_written = true,
            Err(e) => failed_outputs.push(e),
        }
    }
    let report = match report {
        Ok(report) => report,
        Err(e) => {
            for failed in &failed_outputs {
                crate::shared::exit::report(failed);
            }
            return Err(e.into());
        }
    };

    let mut plot_written = false;
    if let (Some(plot), Some(path)) = (plot, &args.plot) {
        let title = format!(
            "{} on {}: planned vs measured",
            file_name(&motion.path),
            robot.name
        );
        match plot.draw(path, &title, &units.to_string()) {
            Ok(()) => plot_written = true,
            Err(e) => failed_outputs.push(e),
        }
    }
    let mut text = Vec::new();
    if args.json {
        let mut value = serde_json::to_value(&report)?;
        if let (Some(r), Some(obj)) = (&recording, value.as_object_mut()) {
            obj.insert("recording".into(), r.json(motion.units));
        }
        writeln!(text, "{}", crate::shared::json::pretty(&value)?)?;
    } else {
        write_report(&mut text, &report, robot.lead.is_none())?;
        if let Some(r) = &recording {
            writeln!(text, "  {}", r.describe(motion.units))?;
        }
        if let (true, Some(path)) = (log_written, &args.log) {
            writeln!(text, "log: {}", path.display())?;
        }
        if let (true, Some(path)) = (plot_written, &args.plot) {
            writeln!(text, "plot: {}", path.display())?;
        }
    }
    let text = String::from_utf8_lossy(&text);
    // The report goes to stdout; once stdout has failed (closed by its
    // reader, or full), to stderr, and the command exits 1 after it.
    let stdout = match stdout {
        Some(e) => Some(e),
        None => out!("{text}").err(),
    };
    if let Some(e) = stdout {
        err!("{text}");
        failed_outputs.push(e.into());
    }
    // An output that failed fails the command (exit 1) after the report:
    // each error is said, the last by `main` as it returns.
    let last = failed_outputs.pop();
    for e in &failed_outputs {
        crate::shared::exit::report(e);
    }
    if let Some(e) = last {
        return Err(e);
    }
    Ok(crate::shared::exit::of_finish(report.finish))
}

fn names_of(robot: &Robot) -> Vec<String> {
    robot.joints().map(|j| j.name.clone()).collect()
}
