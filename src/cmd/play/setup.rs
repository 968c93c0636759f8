//! Where a run of `servobus play` happens: the built-in simulator, a pty
//! server, or real ports.

use super::*;

/// Where the simulated joints start (robot units, robot joint order):
/// `--sim-pose`, checked against the robot, else the rest positions.
pub(super) fn sim_pose(args: &Args, robot: &Robot, backend: &Backend) -> anyhow::Result<Vec<f64>> {
    let Some(pose) = &args.sim_pose else {
        return Ok(robot.joints().map(|j| j.rest()).collect());
    };
    if let Backend::Hardware(_) = backend {
        return Err(crate::cmd::exit::input(
            "--sim-pose sets where the simulator starts; real servos start where they are",
        ));
    }
    if pose.len() != robot.joint_count() {
        return Err(crate::cmd::exit::input(format!(
            "--sim-pose has {} angles; {} has {} joints",
            pose.len(),
            robot.name,
            robot.joint_count()
        )));
    }
    for (j, &a) in robot.joints().zip(pose) {
        if !(j.min..=j.max).contains(&a) {
            return Err(crate::cmd::exit::input(format!(
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
        Ports::Missing(bus) => Err(crate::cmd::link::no_port(robot, &bus.name, None)),
    }
}
