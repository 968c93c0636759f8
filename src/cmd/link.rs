//! Reaching a robot's servos: which port each bus is on, and one way to
//! open a bus on it for every command.
//!
//! The reply deadlines of a bus allow for its adapter's latency. The robot
//! file may give that figure (`latency_us`); otherwise the port says what
//! it needs ([`SerialTransport::assumed_latency`]: an FTDI adapter's timer
//! plus a USB frame, a USB frame for other adapters, a pseudo-terminal's
//! scheduling allowance for a simulator). How much of that a command
//! allows for up front is its [`Allowance`].

use std::sync::OnceLock;
use std::time::Duration;

use anyhow::Context;
use servobus_driver::{Bus, BusSettings, SerialTransport, SystemClock, TransportError};
use servobus_protocol::registers::Series;
use servobus_runtime::bus_settings;
use servobus_runtime::config::{BusConfig, Robot};

/// A bus on a serial port (or a simulator's pseudo-terminal).
pub(crate) type SerialBus = Bus<SerialTransport<SystemClock>, SystemClock>;

/// What a command's reply deadlines allow for the adapter, beyond the
/// robot file's `latency_us`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Allowance {
    /// A timed run (`play`): the robot file's figure, which a run with
    /// `latency_us: auto` learns from at start-up, so a real adapter gets
    /// nothing more up front; a pseudo-terminal gets
    /// [`Link::PTY_LATENCY`], which no probe of a quiet moment would show.
    Run,
    /// What the port is assumed to need
    /// ([`SerialTransport::assumed_latency`]): commands that do not learn
    /// the link (bench, doctor, monitor, teach).
    Assumed,
    /// At least this much: untimed steps that would rather wait than take
    /// a present servo for a missing one (calibration).
    AtLeast(Duration),
}

impl Allowance {
    /// The adapter latency the deadlines allow on `transport`, whose robot
    /// file gives `configured`.
    pub(crate) fn latency(
        self,
        configured: Duration,
        transport: &SerialTransport<SystemClock>,
    ) -> Duration {
        let floor = match self {
            Allowance::Run if transport.is_pty() => transport.assumed_latency(),
            Allowance::Run => Duration::ZERO,
            Allowance::Assumed => transport.assumed_latency(),
            Allowance::AtLeast(d) => d,
        };
        configured.max(floor)
    }
}

/// The clock of every bus this process opens: one epoch, so that the buses
/// of a robot run in step (a run's buses must share their time base).
pub(crate) fn system_clock() -> SystemClock {
    static CLOCK: OnceLock<SystemClock> = OnceLock::new();
    *CLOCK.get_or_init(SystemClock::new)
}

/// Opens `port` at `baud` on the process's one [`SystemClock`].
///
/// # Errors
/// The driver's, which say why the port cannot be opened and what to do.
pub(crate) fn open_port(
    port: &str,
    baud: u32,
) -> Result<SerialTransport<SystemClock>, TransportError> {
    SerialTransport::open(port, baud, system_clock())
}

/// Warns when the port is an FTDI adapter whose latency timer slows every
/// reply down.
pub(crate) fn warn_slow_adapter(transport: &SerialTransport<SystemClock>) {
    if let Some(warning) = transport.ftdi_latency().and_then(|f| f.warning()) {
        eprintln!("warning: {warning}");
    }
}

/// Opens the bus `cfg` of a robot on `port`: its baud rate, busy polling
/// when the robot file (or a flag folded into it) asks for it, its
/// settings, and reply deadlines with `allowance`. Says nothing about the
/// adapter; [`open_bus`] warns about a slow one.
///
/// # Errors
/// When the port cannot be opened, naming the bus.
pub(crate) fn open_bus_quietly(
    cfg: &BusConfig,
    port: &str,
    allowance: Allowance,
) -> anyhow::Result<SerialBus> {
    let mut transport = open_port(port, cfg.baud)
        .with_context(|| format!("bus `{}`: cannot open {port}", cfg.name))?;
    transport.set_busy_poll(cfg.busy_poll);
    let latency = allowance.latency(cfg.latency, &transport);
    Ok(Bus::new(transport, bus_settings(cfg).with_latency(latency)))
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

/// A bus on `port` without a robot file (the bus tools, a monitor that
/// scans): `baud`, the register layout of `series`, and the adapter
/// latency given (`--latency-us`) or else the port's assumed one. Warns
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
    let transport = open_port(port, baud).with_context(|| format!("cannot open {port}"))?;
    warn_slow_adapter(&transport);
    let latency = latency.unwrap_or_else(|| Allowance::Assumed.latency(Duration::ZERO, &transport));
    let settings = BusSettings::new(series).with_latency(latency);
    Ok(Bus::new(transport, settings))
}

/// The port of each bus of `robot`: `port` (the command line's `--port`)
/// for the first, the robot file's `port:` for the others and for the
/// first without `--port`.
pub(crate) fn bus_ports(robot: &Robot, port: Option<&str>) -> Vec<Option<String>> {
    robot
        .buses
        .iter()
        .enumerate()
        .map(|(i, bus)| match (i, port) {
            (0, Some(p)) => Some(p.to_owned()),
            _ => bus.port.clone(),
        })
        .collect()
}

/// Where a robot's buses are, all together.
#[derive(Debug, PartialEq)]
pub(crate) enum Ports<'a> {
    /// No bus has a port: the built-in simulator.
    None,
    /// Every bus has one, in bus order.
    Every(Vec<String>),
    /// Some have one, and this bus (the first without) has none.
    Missing(&'a BusConfig),
}

/// [`bus_ports`] taken together: none, every one, or the first bus missing.
pub(crate) fn every_port<'a>(robot: &'a Robot, port: Option<&str>) -> Ports<'a> {
    let ports = bus_ports(robot, port);
    if ports.iter().all(Option::is_none) {
        return Ports::None;
    }
    let mut every = Vec::with_capacity(ports.len());
    for (bus, port) in robot.buses.iter().zip(ports) {
        match port {
            Some(p) => every.push(p),
            None => return Ports::Missing(bus),
        }
    }
    Ports::Every(every)
}

#[cfg(test)]
mod tests {
    use super::*;
    use servobus_timing::Link;

    fn two_buses(ports: [Option<&str>; 2]) -> Robot {
        let path = servobus::builtin::robot_path_or_name("hexapod-2bus".as_ref());
        let mut robot = servobus_runtime::config::load_robot_any_rate_calibrated(&path, None)
            .expect("the built-in two-bus hexapod loads");
        assert!(robot.buses.len() >= 2, "two buses");
        robot.buses.truncate(2);
        for (bus, port) in robot.buses.iter_mut().zip(ports) {
            bus.port = port.map(str::to_owned);
        }
        robot
    }

    #[test]
    fn a_pty_gets_its_allowance_and_the_robot_file_s_larger_figure_wins() {
        let mut robot = two_buses([None, None]);
        let servos = servobus_runtime::sim::bus_servos(&robot, &robot.buses[0]).expect("servos");
        let server = servobus_sim::PtyServer::open(robot.buses[0].baud, servos).expect("a pty");
        let path = server.path().to_string_lossy().into_owned();
        let pty = open_port(&path, robot.buses[0].baud).expect("the pty opens");
        assert!(pty.is_pty());
        let none = Duration::ZERO;
        assert_eq!(Allowance::Run.latency(none, &pty), Link::PTY_LATENCY);
        assert_eq!(Allowance::Assumed.latency(none, &pty), Link::PTY_LATENCY);
        let patient = Duration::from_millis(50);
        assert_eq!(Allowance::AtLeast(patient).latency(none, &pty), patient);
        let long = Link::PTY_LATENCY * 4;
        assert_eq!(Allowance::Run.latency(long, &pty), long);
        robot.buses[0].latency = long;
        drop(pty); // opened with exclusive access
        let bus = open_bus_quietly(&robot.buses[0], &path, Allowance::Run).expect("a bus");
        assert_eq!(bus.settings().link.latency, long);
    }

    #[test]
    fn the_command_line_port_is_the_first_bus_s_and_the_file_gives_the_rest() {
        let robot = two_buses([Some("/dev/a"), Some("/dev/b")]);
        assert_eq!(
            bus_ports(&robot, Some("/dev/x")),
            [Some("/dev/x".to_owned()), Some("/dev/b".to_owned())]
        );
        assert_eq!(
            every_port(&robot, None),
            Ports::Every(vec!["/dev/a".into(), "/dev/b".into()])
        );
    }

    #[test]
    fn no_port_anywhere_is_the_simulator_and_a_partial_set_names_the_bus_without() {
        let robot = two_buses([None, None]);
        assert_eq!(every_port(&robot, None), Ports::None);
        let Ports::Missing(bus) = every_port(&robot, Some("/dev/x")) else {
            panic!("the second bus has no port");
        };
        assert_eq!(bus.name, robot.buses[1].name);
        let robot = two_buses([None, Some("/dev/b")]);
        let Ports::Missing(bus) = every_port(&robot, None) else {
            panic!("the first bus has no port");
        };
        assert_eq!(bus.name, robot.buses[0].name);
    }
}
