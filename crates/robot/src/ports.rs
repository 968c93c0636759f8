//! Reaching a robot's servos: which port each bus is on, and one way to
//! open a bus on it for every program.
//!
//! The reply deadlines of a bus allow for its adapter's latency. The robot
//! file may give that figure (`latency_us`); otherwise the port says what
//! it needs ([`SerialTransport::assumed_latency`]: an FTDI adapter's timer
//! plus a USB frame, a USB frame for other adapters, a pseudo-terminal's
//! scheduling allowance for a simulator). How much of that a program
//! allows for up front is its [`Allowance`].
//!
//! Nothing here prints: an FTDI adapter whose latency timer slows every
//! reply down is returned as data ([`slow_adapter`]), for the program to
//! show as it likes.

use std::sync::OnceLock;
use std::time::Duration;

use servobus_config::{BusConfig, Robot};
use servobus_driver::{
    Bus, BusSettings, FtdiLatency, SerialTransport, Series, SystemClock, TransportError,
};
use servobus_runtime::bus_settings;

/// A bus on a serial port (or a simulator's pseudo-terminal).
pub type SerialBus = Bus<SerialTransport<SystemClock>>;

/// A port that cannot be opened. Its source, the driver's error, says why
/// and what to do (a group to join, the ports present, who holds the port).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OpenError {
    /// The port of one of the robot's buses.
    #[error("bus `{bus}`: cannot open {port}")]
    Bus {
        /// The bus.
        bus: String,
        /// Its port.
        port: String,
        /// Why (the driver says what to do: a group to join, the ports
        /// present, who holds the port).
        #[source]
        source: TransportError,
    },
    /// A port opened without a robot file.
    #[error("cannot open {port}")]
    Port {
        /// The port.
        port: String,
        /// Why.
        #[source]
        source: TransportError,
    },
}

/// What a program's reply deadlines allow for the adapter, beyond the
/// robot file's `latency_us`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Allowance {
    /// A timed run (play): the robot file's figure, which a run with
    /// `latency_us: auto` learns from at start-up, so a real adapter gets
    /// nothing more up front; a pseudo-terminal gets
    /// [`servobus_driver::Link::PTY_LATENCY`], which no probe of a quiet
    /// moment would show.
    Run,
    /// What the port is assumed to need
    /// ([`SerialTransport::assumed_latency`]): programs that do not learn
    /// the link (bench, doctor, monitor, teach).
    Assumed,
    /// At least this much: untimed steps that would rather wait than take
    /// a present servo for a missing one (calibration).
    AtLeast(Duration),
}

impl Allowance {
    /// The adapter latency the deadlines allow on `transport`, whose robot
    /// file gives `configured`.
    pub fn latency(
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
pub fn system_clock() -> SystemClock {
    static CLOCK: OnceLock<SystemClock> = OnceLock::new();
    *CLOCK.get_or_init(SystemClock::new)
}

/// Opens `port` at `baud` on the process's one [`SystemClock`].
///
/// # Errors
/// The driver's, which say why the port cannot be opened and what to do.
pub fn open_port(port: &str, baud: u32) -> Result<SerialTransport<SystemClock>, TransportError> {
    SerialTransport::open(port, baud, system_clock())
}

/// The FTDI latency timer of the adapter behind `transport` when it slows
/// every reply down (above 1 ms); [`FtdiLatency::warning`] says how to fix it.
pub fn slow_adapter(transport: &SerialTransport<SystemClock>) -> Option<FtdiLatency> {
    transport
        .ftdi_latency()
        .filter(|f| f.is_too_high())
        .cloned()
}

/// Opens the bus `cfg` of a robot on `port`: its baud rate, busy polling
/// when the robot file asks for it, its settings, and reply deadlines with
/// `allowance`. A slow adapter is for the caller to find
/// ([`slow_adapter`] of the bus's transport).
///
/// # Errors
/// [`OpenError::Bus`] when the port cannot be opened.
pub fn open_bus(cfg: &BusConfig, port: &str, allowance: Allowance) -> Result<SerialBus, OpenError> {
    let mut transport = open_port(port, cfg.baud).map_err(|source| OpenError::Bus {
        bus: cfg.name.clone(),
        port: port.to_owned(),
        source,
    })?;
    transport.set_busy_poll(cfg.busy_poll);
    let latency = allowance.latency(cfg.latency, &transport);
    Ok(Bus::new(transport, bus_settings(cfg).with_latency(latency)))
}

/// Opens every bus of `robot` on `ports` (one per bus, in order; see
/// [`every_port`]) with `allowance`, and `retries` tries more per
/// transaction when given (else the robot file's bus settings').
///
/// # Errors
/// [`OpenError::Bus`] for the first port that cannot be opened.
pub fn open_buses(
    robot: &Robot,
    ports: &[String],
    allowance: Allowance,
    retries: Option<u8>,
) -> Result<Vec<SerialBus>, OpenError> {
    let mut buses = Vec::with_capacity(ports.len());
    for (cfg, port) in robot.buses.iter().zip(ports) {
        let mut bus = open_bus(cfg, port, allowance)?;
        if let Some(retries) = retries {
            bus.set_settings(bus.settings().with_retries(retries));
        }
        buses.push(bus);
    }
    Ok(buses)
}

/// A bus on `port` without a robot file (the bus tools, a monitor that
/// scans): `baud`, the register layout of `series`, and the adapter
/// latency given or else the port's assumed one.
///
/// # Errors
/// [`OpenError::Port`] when the port cannot be opened.
pub fn open_plain_bus(
    port: &str,
    baud: u32,
    series: Series,
    latency: Option<Duration>,
) -> Result<SerialBus, OpenError> {
    let transport = open_port(port, baud).map_err(|source| OpenError::Port {
        port: port.to_owned(),
        source,
    })?;
    let latency = latency.unwrap_or_else(|| Allowance::Assumed.latency(Duration::ZERO, &transport));
    let settings = BusSettings::new(series).with_latency(latency);
    Ok(Bus::new(transport, settings))
}

/// The port of each bus of `robot`: `overrides[i]` (a port the program
/// gives, the command line's `--port` for the first bus) for bus `i`, the
/// robot file's `port:` for the buses past them.
pub fn bus_ports<S: AsRef<str>>(robot: &Robot, overrides: &[S]) -> Vec<Option<String>> {
    robot
        .buses
        .iter()
        .enumerate()
        .map(|(i, bus)| match overrides.get(i) {
            Some(p) => Some(p.as_ref().to_owned()),
            None => bus.port.clone(),
        })
        .collect()
}

/// Where a robot's buses are, all together.
#[derive(Debug, PartialEq)]
pub enum Ports<'a> {
    /// No bus has a port: the built-in simulator.
    None,
    /// Every bus has one, in bus order.
    Every(Vec<String>),
    /// Some have one, and this bus (the first without) has none.
    Missing(&'a BusConfig),
}

impl Ports<'_> {
    /// Every bus's port, or [`Error::NoPort`](crate::Error::NoPort) naming
    /// the first bus without one (the first bus of `robot` when none has
    /// one).
    ///
    /// # Errors
    /// [`Error::NoPort`](crate::Error::NoPort).
    pub fn required(self, robot: &Robot) -> Result<Vec<String>, crate::Error> {
        let bus = match self {
            Ports::Every(ports) => return Ok(ports),
            Ports::Missing(bus) => bus.name.clone(),
            Ports::None => robot
                .buses
                .first()
                .map(|b| b.name.clone())
                .unwrap_or_default(),
        };
        Err(crate::Error::NoPort { bus })
    }
}

/// [`bus_ports`] taken together: none, every one, or the first bus missing.
pub fn every_port<'a, S: AsRef<str>>(robot: &'a Robot, overrides: &[S]) -> Ports<'a> {
    let ports = bus_ports(robot, overrides);
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
    use servobus_config::builtin;
    use servobus_config::{load_robot, RobotOptions};
    use servobus_driver::Link;

    fn two_buses(ports: [Option<&str>; 2]) -> Robot {
        let path = builtin::robot_path_or_name("hexapod-2bus".as_ref());
        let mut robot = load_robot(&path, &RobotOptions::default().any_rate())
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
        let servos = crate::sim::bus_servos(&robot, &robot.buses[0]).expect("servos");
        let server = servobus_sim::PtyServer::open(robot.buses[0].baud, servos).expect("a pty");
        let path = server.path().to_string_lossy().into_owned();
        let pty = open_port(&path, robot.buses[0].baud).expect("the pty opens");
        assert!(pty.is_pty());
        assert_eq!(slow_adapter(&pty), None, "a pty is no FTDI adapter");
        let none = Duration::ZERO;
        assert_eq!(Allowance::Run.latency(none, &pty), Link::PTY_LATENCY);
        assert_eq!(Allowance::Assumed.latency(none, &pty), Link::PTY_LATENCY);
        let patient = Duration::from_millis(50);
        assert_eq!(Allowance::AtLeast(patient).latency(none, &pty), patient);
        let long = Link::PTY_LATENCY * 4;
        assert_eq!(Allowance::Run.latency(long, &pty), long);
        robot.buses[0].latency = long;
        drop(pty); // opened with exclusive access
        let bus = open_bus(&robot.buses[0], &path, Allowance::Run).expect("a bus");
        assert_eq!(bus.settings().link.latency, long);
    }

    #[test]
    fn every_bus_opens_with_the_tries_asked_for_or_its_own() {
        let mut robot = two_buses([None, None]);
        robot.buses.truncate(1);
        let servos = crate::sim::bus_servos(&robot, &robot.buses[0]).expect("servos");
        let server = servobus_sim::PtyServer::open(robot.buses[0].baud, servos).expect("a pty");
        let path = vec![server.path().to_string_lossy().into_owned()];
        let own = servobus_runtime::bus_settings(&robot.buses[0]).retries;
        let buses = open_buses(&robot, &path, Allowance::Assumed, None).expect("opens");
        assert_eq!(buses.len(), 1);
        assert_eq!(buses[0].settings().retries, own);
        drop(buses); // opened with exclusive access
        let buses = open_buses(&robot, &path, Allowance::Assumed, Some(own + 3)).expect("opens");
        assert_eq!(buses[0].settings().retries, own + 3);
        let missing = ["/dev/servobus-no-such-port".to_owned()];
        match open_buses(&robot, &missing, Allowance::Assumed, None) {
            Err(OpenError::Bus { bus, .. }) => assert_eq!(bus, robot.buses[0].name),
            other => panic!("expected OpenError::Bus, got {:?}", other.map(|b| b.len())),
        }
    }

    #[test]
    fn a_port_that_does_not_exist_is_a_typed_error_naming_the_bus() {
        let robot = two_buses([None, None]);
        let missing = "/dev/servobus-no-such-port";
        match open_bus(&robot.buses[0], missing, Allowance::Assumed) {
            Err(OpenError::Bus { bus, port, .. }) => {
                assert_eq!(bus, robot.buses[0].name);
                assert_eq!(port, missing);
            }
            other => panic!("expected OpenError::Bus, got {other:?}"),
        }
        let plain = open_plain_bus(missing, 1_000_000, Series::Sts, None);
        assert!(matches!(plain, Err(OpenError::Port { port, .. }) if port == missing));
    }

    #[test]
    fn the_override_is_the_first_bus_s_port_and_the_file_gives_the_rest() {
        let robot = two_buses([Some("/dev/a"), Some("/dev/b")]);
        assert_eq!(
            bus_ports(&robot, &["/dev/x"]),
            [Some("/dev/x".to_owned()), Some("/dev/b".to_owned())]
        );
        assert_eq!(
            every_port::<&str>(&robot, &[]),
            Ports::Every(vec!["/dev/a".into(), "/dev/b".into()])
        );
    }

    #[test]
    fn no_port_anywhere_is_the_simulator_and_a_partial_set_names_the_bus_without() {
        let robot = two_buses([None, None]);
        assert_eq!(every_port::<&str>(&robot, &[]), Ports::None);
        assert!(matches!(
            every_port::<&str>(&robot, &[]).required(&robot),
            Err(crate::Error::NoPort { bus }) if bus == robot.buses[0].name
        ));
        let Ports::Missing(bus) = every_port(&robot, &["/dev/x"]) else {
            panic!("the second bus has no port");
        };
        assert_eq!(bus.name, robot.buses[1].name);
        let robot = two_buses([None, Some("/dev/b")]);
        let Ports::Missing(bus) = every_port::<&str>(&robot, &[]) else {
            panic!("the first bus has no port");
        };
        assert_eq!(bus.name, robot.buses[0].name);
        let both = every_port(&robot, &["/dev/a", "/dev/c"]);
        assert_eq!(
            both.required(&robot).ok(),
            Some(vec!["/dev/a".to_owned(), "/dev/c".to_owned()])
        );
    }
}
