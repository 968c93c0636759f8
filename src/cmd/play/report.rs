//! The plan printed before a run of `servobus play` and the report after it.

use super::*;
use crate::shared::out::outln;

pub(super) fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    )
}

pub(super) fn print_plan(
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
    outln!(
        "{} on {} ({} joints, {} bus{}) via {on}",
        file_name(&motion.path),
        robot.name,
        robot.joint_count(),
        robot.buses.len(),
        if robot.buses.len() == 1 { "" } else { "es" },
    )?;
    if motion.keyframes.is_empty() {
        // A recording has samples, not keyframes (its figures follow the
        // plan).
        outln!(
            "  path {:.2} s through a recording, at {rate_hz} Hz",
            trajectory.duration()
        )?;
    } else {
        outln!(
            "  path {:.2} s, {} keyframes x {}, at {rate_hz} Hz",
            trajectory.duration(),
            motion.keyframes.len(),
            motion.repeat
        )?;
    }
    for bus in &robot.buses {
        let plan = bus.plan(rate_hz)?;
        let every = if plan.read_every() > 1 {
            format!(", each servo read every {} cycles", plan.read_every())
        } else {
            String::new()
        };
        outln!(
            "  bus {}: {} servos at {} baud, {} B and {:.0} us per cycle, {:.1} % of the period \
             (max {:.0} Hz){every}",
            bus.name,
            plan.servos(),
            bus.baud,
            plan.bytes_per_cycle(),
            plan.cycle_time_us(),
            100.0 * plan.utilisation(),
            plan.fastest_rate_hz(),
        )?;
    }
    Ok(())
}
