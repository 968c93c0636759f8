//! `servobus play`: a choreography on the simulated robot or on real servos.
//!
//! Everything is checked before anything moves: both files, every keyframe
//! against the joint limits, the path against the velocity, acceleration and
//! jerk limits, and the rate against every bus's budget. Then the plan is
//! printed in one short block, the run starts (on real servos, with a slow
//! approach from wherever the joints are to the first keyframe), a progress
//! line follows it, and a report closes it.

use std::process::ExitCode;

use servobus_config::{Motion, Robot};
use servobus_robot::Trajectory;

use crate::record::CsvLog;
use crate::shared::flags::Recording;

// `run` below is the order of events; each step's details live by concern:
// reading the inputs, where the run happens, what is shown while it runs
// and after.
mod args;
mod load;
mod report;
mod setup;
mod view;

use crate::shared::install_ctrl_c;
pub use args::Args;
use load::{check_outputs, load, names_of, RecordingInfo};
use report::{print_plan, report_text, Outputs};
use setup::{backend, run_options, sim_pose, start, Backend};
use view::{follow, Followed, Shown, SETTLE};

use crate::shared::out::outln;

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
        rerun,
    } = prepare(&args)?;
    let units = motion.units;
    let duration = trajectory.duration();
    // The first keyframe is the path's start; each segment ends at the next.
    let keyframes: Vec<f64> = std::iter::once(0.0)
        .chain(trajectory.segments().iter().map(|s| s.end))
        .collect();
    let mut options = run_options(&args, &robot, units, rate_hz);
    // A keyframe's `grasp:` grasps from the start of its move.
    options.grasps = servobus_robot::motion_grasps(&motion, &trajectory);
    let started = start(
        &backend,
        &robot,
        &pose,
        trajectory,
        options,
        (rate_hz, args.store.write_servos),
    );
    let (runner, mut rerun) = rerun.unless_refused(started)?;
    install_ctrl_c(runner.commands());
    let recorded = recording.as_ref().map(|r| r.series.as_slice());
    let shown = shown_of(&robot, keyframes, &runner, recorded);
    let outcome = if args.monitor {
        crate::shared::screen::watch_run(&runner, &robot, units, rate_hz).map(|()| Followed {
            log: None,
            plot: None,
            stdout: None,
        })
    } else {
        follow(&runner, &args, (log, &mut rerun), &shown, units, duration)
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
            let e = e.into();
            rerun.refused(&e);
            outputs.finish_rerun(rerun);
            outputs.say_failed();
            return Err(e);
        }
    };
    outputs.finish_rerun(rerun);
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

/// What the live view and the plot show of `robot`'s run of a path with
/// `keyframes` (path times) on `runner`, beside the `recording` replayed.
fn shown_of<'a>(
    robot: &Robot,
    keyframes: Vec<f64>,
    runner: &servobus_robot::Run,
    recording: Option<&'a [Vec<(f64, f64)>]>,
) -> Shown<'a> {
    Shown {
        names: names_of(robot),
        bus_of: robot
            .buses
            .iter()
            .flat_map(|bus| bus.joints.iter().map(|_| bus.name.clone()))
            .collect(),
        keyframes,
        approach: runner.approach().as_secs_f64(),
        settle: SETTLE.as_secs_f64(),
        geometry: robot.geometry(),
        recording,
    }
}

/// What is known and made before anything moves.
struct Prepared {
    motion: Motion,
    robot: Robot,
    trajectory: Trajectory,
    recording: Option<RecordingInfo>,
    rate_hz: f64,
    backend: Backend,
    /// Where the simulated joints start.
    pose: Vec<f64>,
    /// The log's temporary, with `--log`.
    log: Option<CsvLog>,
    /// The recording for the Rerun viewer, with `--rerun` or
    /// `--rerun-connect`.
    rerun: Recording,
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
    args.rerun.check()?;
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
            servobus_robot::odometry::Odometer::of(&robot, motion.units),
        )?),
        None => None,
    };
    // Its temporary (or the viewer's connection) too: the robot's tree and
    // meshes are logged before anything moves.
    let rerun = args.rerun.start(&robot, motion.units)?;
    Ok(Prepared {
        motion,
        robot,
        trajectory,
        recording,
        rate_hz,
        backend,
        pose,
        log,
        rerun,
    })
}
