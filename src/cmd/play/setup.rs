//! Where a run of `servobus play` happens: the built-in simulator, a pty
//! server, or real ports.

use anyhow::Context;

use servobus_config::{Robot, Units};
use servobus_robot::{Lead, RtOptions, Run, RunOptions, Trajectory};

use super::args::Args;
use super::view::{APPROACH, SETTLE};
use crate::shared::ports::{every_port, Ports};

/// Where the run happens.
pub(super) enum Backend {
    /// Simulated buses in virtual time.
    Fast,
    /// The simulator on pseudo-terminals, in wall-clock time.
    Simulated,
    /// Real servos: one port per bus.
    Hardware(Vec<String>),
}

/// Where the simulated joints start (robot units, robot joint order):
/// `--sim-pose`, checked against the robot, else the rest positions.
pub(super) fn sim_pose(args: &Args, robot: &Robot, backend: &Backend) -> anyhow::Result<Vec<f64>> {
    let Some(pose) = &args.sim_pose else {
        return Ok(robot.joints().map(|j| j.rest()).collect());
    };
    if let Backend::Hardware(_) = backend {
        return Err(crate::shared::exit::input(
            "--sim-pose sets where the simulator starts; real servos start where they are",
        ));
    }
    if pose.len() != robot.joint_count() {
        return Err(crate::shared::exit::input(format!(
            "--sim-pose has {} angles; {} has {} joints",
            pose.len(),
            robot.name,
            robot.joint_count()
        )));
    }
    for (j, &a) in robot.joints().zip(pose) {
        if !(j.min..=j.max).contains(&a) {
            return Err(crate::shared::exit::input(format!(
                "--sim-pose: {} = {a} is outside its limits {}..{}",
                j.name, j.min, j.max
            )));
        }
    }
    Ok(pose.clone())
}

pub(super) fn backend(args: &Args, robot: &Robot) -> anyhow::Result<Backend> {
    if args.fast {
        return Ok(Backend::Fast);
    }
    match every_port(robot, args.hardware.port.as_slice()) {
        Ports::None => Ok(Backend::Simulated),
        Ports::Every(ports) => Ok(Backend::Hardware(ports)),
        Ports::Missing(bus) => Err(crate::shared::ports::no_port(robot, &bus.name, None)),
    }
}

/// On real ports, the rate checked again once each adapter of a bus with
/// `latency_us: auto` is measured: the start-up probe `budget --port` runs
/// (`measure_link`), and the maximum rate it prints on that link. The check
/// of the robot file's figures (in `load`) knew no adapter latency.
///
/// # Errors
///
/// A usage error (exit 2) when the rate does not fit a measured adapter;
/// the bus's error when no servo answers the probe.
pub(super) fn check_measured_rates(
    connection: &mut servobus_robot::Connection,
    ports: &[String],
    rate_hz: f64,
) -> anyhow::Result<()> {
    let configs = connection.robot().buses.clone();
    let Some(serial) = connection.serial_buses() else {
        return Ok(());
    };
    for ((config, bus), port) in configs.iter().zip(serial.iter_mut()).zip(ports) {
        if !config.latency_auto {
            continue;
        }
        let pty = bus.transport().is_pty();
        let measured = servobus_robot::bench::measure_link(bus, config, pty)
            .with_context(|| format!("measuring the adapter on {port}"))?;
        if let Err(why) = config.check_rate_on(&measured.link, rate_hz) {
            return Err(crate::shared::exit::input(format!(
                "bus `{}` on {port} (adapter measured: {:.0} us a PING beyond the wire and the servo): {}",
                config.name,
                measured.ping_latency.as_secs_f64() * 1e6,
                crate::shared::flags::rate_advice(&why)
            )));
        }
    }
    Ok(())
}

/// The run's options: the rate, the units, the settling and approach, the
/// lead, and the control threads' core and priority.
pub(super) fn run_options(args: &Args, robot: &Robot, units: Units, rate_hz: f64) -> RunOptions {
    RunOptions {
        rate_hz: Some(rate_hz),
        units: Some(units),
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
    }
}

/// Starts playing `trajectory` where `backend` says: the simulated joints
/// from `pose`, real servos once their measured rates are checked (what
/// the robot file asks of their EEPROM stored first with `write_servos`).
pub(super) fn start(
    backend: &Backend,
    robot: &Robot,
    pose: &[f64],
    trajectory: Trajectory,
    options: RunOptions,
    (rate_hz, write_servos): (f64, bool),
) -> anyhow::Result<Run> {
    Ok(match backend {
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
                .connect_at(target, pose)?
                .play(trajectory, options)?
        }
        Backend::Hardware(ports) => {
            let mut connection = crate::shared::ports::connect(
                robot,
                servobus_robot::Target::Ports(ports.to_vec()),
                write_servos,
            )?;
            check_measured_rates(&mut connection, ports, rate_hz)?;
            connection.play(trajectory, options)?
        }
    })
}
