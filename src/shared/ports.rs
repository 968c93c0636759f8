//! Reaching a robot's servos from the command line: the library's
//! ([`servobus_robot::ports`]), with a slow FTDI adapter said on stderr.

use std::time::Duration;

use servobus_config::{BusConfig, Robot};
use servobus_robot::bus::{SerialTransport, Series, SystemClock};
use servobus_robot::{ports, Connection, Target};

use super::out::errln;

pub(crate) use servobus_robot::ports::{
    bus_ports, every_port, system_clock, Allowance, Ports, SerialBus,
};

/// Warns when the port is an FTDI adapter whose latency timer slows every
/// reply down.
fn warn_slow_adapter(transport: &SerialTransport<SystemClock>) {
    if let Some(warning) = ports::slow_adapter(transport).and_then(|f| f.warning()) {
        errln!("warning: {warning}");
    }
}

/// Opens the bus `cfg` of a robot on `port` ([`ports::open_bus`]); says
/// nothing about the adapter.
///
/// # Errors
/// When the port cannot be opened, naming the bus.
pub(crate) fn open_bus_quietly(
    cfg: &BusConfig,
    port: &str,
    allowance: Allowance,
) -> anyhow::Result<SerialBus> {
    Ok(ports::open_bus(cfg, port, allowance)?)
}

/// [`open_bus_quietly`], warning about a slow FTDI adapter.
///
/// # Errors
/// When the port cannot be opened, naming the bus.
pub(crate) fn open_bus(
    cfg: &BusConfig,
    port: &str,
    allowance: Allowance,
) -> anyhow::Result<SerialBus> {
    let bus = open_bus_quietly(cfg, port, allowance)?;
    warn_slow_adapter(bus.transport());
    Ok(bus)
}

/// Every bus of `robot` on `ports` ([`ports::open_buses`]), warning about
/// each slow FTDI adapter.
///
/// # Errors
/// When a port cannot be opened, naming the bus.
pub(crate) fn open_buses(
    robot: &Robot,
    ports: &[String],
    allowance: Allowance,
    retries: Option<u8>,
) -> anyhow::Result<Vec<SerialBus>> {
    let buses = ports::open_buses(robot, ports, allowance, retries)?;
    for bus in &buses {
        warn_slow_adapter(bus.transport());
    }
    Ok(buses)
}

/// A bus on `port` without a robot file ([`ports::open_plain_bus`], the
/// latency given by `--latency-us` or else the port's assumed one), warning
/// about a slow FTDI adapter.
///
/// # Errors
/// When the port cannot be opened.
pub(crate) fn open_plain_bus(
    port: &str,
    baud: u32,
    series: Series,
    latency: Option<Duration>,
) -> anyhow::Result<SerialBus> {
    let bus = ports::open_plain_bus(port, baud, series, latency)?;
    warn_slow_adapter(bus.transport());
    Ok(bus)
}

/// The command line's one message for `robot`'s bus `bus` that has no port
/// (an input error), with the command's own `hint` after it, if any.
pub(crate) fn no_port(robot: &Robot, bus: &str, hint: Option<&str>) -> anyhow::Error {
    let hint = hint.map_or(String::new(), |h| format!("; {h}"));
    super::exit::input(format!(
        "bus `{bus}` has no port: give --port (it sets the first bus's), and every other bus \
         a `port:` in the robot file {}{hint}",
        robot.path.display()
    ))
}

/// Connects to `robot`'s buses at `target` through the library (on ports,
/// each opened for a run and the calibration checked; with `write_servos`
/// what the robot file asks of the servos' EEPROM stored first, each
/// register stored said on stderr), saying a slow FTDI adapter on stderr
/// and what to run when the servos do not match the calibration.
///
/// # Errors
/// When a port cannot be opened, a servo does not take a write, or the
/// servos are refused.
pub(crate) fn connect(
    robot: &Robot,
    target: Target,
    write_servos: bool,
) -> anyhow::Result<Connection> {
    let options = servobus_robot::ConnectOptions { write_servos };
    let connection = servobus_robot::Robot::from(robot.clone())
        .connect_with(target, options)
        .map_err(|e| match e {
            servobus_robot::Error::Refused { port, refusal, .. } => {
                super::refusal::refused(robot, &refusal, &port)
            }
            servobus_robot::Error::NoPort { bus } => no_port(robot, &bus, None),
            e => e.into(),
        })?;
    for stored in connection.stored_settings() {
        errln!("{stored}");
    }
    for slow in connection.slow_adapters() {
        if let Some(warning) = slow.timer.warning() {
            errln!("warning: {warning}");
        }
    }
    Ok(connection)
}

/// Starts a live run of `robot` through the library's connection: on its
/// ports (`port` for the first bus), through its calibration (what the
/// robot file asks of the servos' EEPROM stored first with
/// `write_servos`), or on the built-in simulator in real time.
pub(crate) fn start_live(
    robot: &Robot,
    port: Option<&str>,
    options: servobus_robot::RunOptions,
    write_servos: bool,
) -> anyhow::Result<servobus_robot::Run> {
    let target = match every_port(robot, port.as_slice()) {
        Ports::None => servobus_robot::Target::Simulator,
        Ports::Every(ports) => servobus_robot::Target::Ports(ports),
        Ports::Missing(bus) => return Err(no_port(robot, &bus.name, None)),
    };
    let connection = connect(robot, target, write_servos)?;
    Ok(connection.live(options)?)
}
