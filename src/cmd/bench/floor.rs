//! The pseudo-terminal's own request/reply floor for a bus's cycle, measured
//! in the same run as `bench` on the simulator.

use std::time::Duration;

use anyhow::Context;
use servobus_config::BusConfig;
use servobus_robot::sim::{pty_floor, FloorCycle};
use servobus_robot::timing::{sync_write_bytes, Block};

/// Bytes of a status packet's frame around its data (header 2, ID, length,
/// error, checksum), and of a request around its parameters (header 2, ID,
/// length, instruction, checksum).
const FRAME: usize = 6;

/// The bytes of `bus`'s cycle as the floor exchanges them: the SYNC WRITE of
/// every goal, then one SYNC READ answered by every servo, or (on buses
/// whose servos lack SYNC READ) one READ per servo answered by that servo.
/// A bus mixing both is measured as all READs, the slower shape.
pub(super) fn cycle_of(bus: &BusConfig) -> FloorCycle {
    let n = bus.joints.len();
    let len = usize::from(Block::PRESENT_POSITION.len);
    let write = sync_write_bytes(n, Block::GOAL_POSITION.len);
    let reply_one = FRAME + len;
    // Each reply comes after its servo's turnaround and return delay, as
    // the simulator answers (the slowest model on the bus, for every reply).
    let per_reply = bus
        .joints
        .iter()
        .map(|j| j.model.turnaround)
        .max()
        .unwrap_or_default()
        + bus.return_delay;
    if bus.joints.iter().all(|j| j.model.series.has_sync_read()) {
        // SYNC READ: address, length and one ID per servo.
        FloorCycle {
            baud: bus.baud,
            write,
            read: FRAME + 2 + n,
            reply: n * reply_one,
            trips: 1,
            servo: per_reply * u32::try_from(n).unwrap_or(u32::MAX),
        }
    } else {
        // READ: address and length.
        FloorCycle {
            baud: bus.baud,
            write,
            read: FRAME + 2,
            reply: reply_one,
            trips: n.max(1),
            servo: per_reply,
        }
    }
}

/// The floor's mean rate for `bus`'s cycle over `duration`, Hz.
pub(super) fn floor_rate_hz(bus: &BusConfig, duration: Duration) -> anyhow::Result<f64> {
    let floor = pty_floor(cycle_of(bus), duration)
        .with_context(|| format!("bus `{}`: measuring the pty's floor", bus.name))?;
    Ok(floor.rate_hz())
}
