//! Opening the bus for a tool: the port at its baud rate and latency, and
//! for a single-servo tool the servo checked and identified.

use std::time::Duration;

use anyhow::Context;
use servobus_protocol::registers::{addr, Series};
use servobus_protocol::MAX_ID;
use servobus_robot::scan::{adapt_latency, identify, Found};

use super::args::{PortArgs, ServoArgs};
use crate::shared::exit::input;
use crate::shared::ports::{open_plain_bus, SerialBus};

/// Opens the port and builds a bus; warns about a slow FTDI latency timer.
pub(super) fn open(
    port: &PortArgs,
    baud: u32,
    series: Series,
    retries: u8,
) -> anyhow::Result<SerialBus> {
    let latency = port.latency_us.map(Duration::from_micros);
    let mut bus = open_plain_bus(&port.port, baud, series, latency)?;
    bus.set_settings(bus.settings().with_retries(retries));
    Ok(bus)
}

/// Refuses an ID above the servos' range (an input error).
pub(super) fn check_id(id: u8) -> anyhow::Result<()> {
    if id > MAX_ID {
        return Err(input(format!("ID {id} is not a servo ID (0..={MAX_ID})")));
    }
    Ok(())
}

/// Opens the bus and learns the servo's series from its model number.
pub(super) fn open_servo(servo: &ServoArgs) -> anyhow::Result<(SerialBus, Found)> {
    let ServoArgs { port, baud, id } = servo;
    let (baud, id) = (*baud, *id);
    check_id(id)?;
    let mut bus = open(port, baud, Series::Sts, 2)?;
    if port.latency_us.is_none() {
        adapt_latency(&mut bus, id).with_context(|| format!("servo {id}"))?;
    }
    let found = identify(&mut bus, id).with_context(|| {
        format!(
            "servo {id} at {baud} baud (to find the servos and their rates: \
             servobus scan --port {} --all-bauds)",
            port.port
        )
    })?;
    // A servo at a status level that leaves WRITE unanswered (0 on STS,
    // below 2 on SCS) is written without waiting for replies, so that
    // `servobus write ... status_level 1` (doctor's fix) can reach it.
    let mut level = [0u8; 1];
    if bus.read(id, addr::STATUS_LEVEL, &mut level).is_ok() {
        let series = bus.settings().series;
        let s = bus
            .settings()
            .with_replies(servobus_robot::bus::StatusLevel::from_register(
                series, level[0],
            ));
        bus.set_settings(s);
    }
    Ok((bus, found))
}
