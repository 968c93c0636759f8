//! Connecting to a robot's buses: serial ports or the built-in simulator,
//! with the calibration checked before anything is read or moved.

use std::fmt;
use std::time::Duration;

use crate::calibrate::prepare_bus;
use crate::doctor::{store_wanted_settings, StoredSetting};
use crate::sim::SimRobot;
use servobus_config::Robot;
use servobus_driver::FtdiLatency;
use servobus_runtime::{Lead, RunOptions};

use crate::ports::{every_port, open_bus, slow_adapter, system_clock, Allowance, SerialBus};
use crate::Error;

/// How long a run holds (and tracks) the final position after the path, by
/// default: long enough for the servos to settle, so that the report
/// includes it.
pub const SETTLE: Duration = Duration::from_millis(300);

/// The fraction of the joint limits a run approaches the path's start at,
/// by default (slowly: the joints may be anywhere).
pub const APPROACH: f64 = 0.25;

/// Where a robot's buses are.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Target {
    /// The ports of the robot file (each bus's `port:`).
    RobotFile,
    /// These ports, the first for the robot's first bus and so on; a bus
    /// past the list is on the robot file's port.
    Ports(Vec<String>),
    /// The built-in simulator in this process, in virtual time: a run takes
    /// as long as the computer needs, not as long as the motion.
    VirtualSimulator,
    /// The built-in simulator in this process, paced by the wall clock.
    Simulator,
}

/// What connecting does beside opening the buses and checking them.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ConnectOptions {
    /// On serial ports: store in each servo's EEPROM what the robot file
    /// asks of it and it does not hold (its joint's operating mode, the
    /// EEPROM `servo:` settings), before the calibration is checked
    /// ([`crate::doctor::store_wanted_settings`]). Without it nothing is
    /// written to EEPROM and a servo in the wrong operating mode is
    /// refused when the run starts. The built-in simulator's servos are
    /// the robot file's design: nothing to store.
    pub write_servos: bool,
}

/// An FTDI adapter whose latency timer slows every reply of a bus down.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SlowAdapter {
    /// The bus.
    pub bus: String,
    /// Its adapter's timer, and where to set it.
    pub timer: FtdiLatency,
}

impl fmt::Display for SlowAdapter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.timer.warning() {
            Some(w) => write!(f, "bus `{}`: {w}", self.bus),
            None => write!(f, "bus `{}`: FTDI latency timer", self.bus),
        }
    }
}

/// The buses of a connection.
enum Buses {
    /// Serial ports (real servos, or a `servobus sim` pty).
    Serial(Vec<SerialBus>),
    /// The built-in simulator in virtual time.
    Virtual(SimRobot),
    /// The built-in simulator paced by the wall clock.
    Wall(SimRobot),
}

/// A robot's buses, open and checked: on serial ports, the servos found
/// match the robot's calibration, each calibrated servo in its play frame
/// (the runtime's `prepare_bus`, bus by bus), as before every run of the
/// command line. Play on it with
/// [`Connection::play`].
///
/// The built-in simulator's servos are the robot file's design; as on the
/// command line, they are not checked against a calibration.
pub struct Connection {
    pub(crate) robot: Robot,
    buses: Buses,
    slow: Vec<SlowAdapter>,
    stored: Vec<StoredSetting>,
}

impl fmt::Debug for Connection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let on = match &self.buses {
            Buses::Serial(b) => format!("{} serial buses", b.len()),
            Buses::Virtual(_) => "the simulator in virtual time".to_owned(),
            Buses::Wall(_) => "the simulator on the wall clock".to_owned(),
        };
        f.debug_struct("Connection")
            .field("robot", &self.robot.name)
            .field("on", &on)
            .finish()
    }
}

/// The port of each bus of `robot` at `ports` (the file's beyond them).
fn resolve(robot: &Robot, ports: &[String]) -> Result<Vec<String>, Error> {
    if ports.len() > robot.buses.len() {
        return Err(Error::TooManyPorts {
            given: ports.len(),
            buses: robot.buses.len(),
        });
    }
    every_port(robot, ports).required(robot)
}

impl Connection {
    /// Opens `robot`'s buses at `target`, stores what the robot file asks
    /// of the servos' EEPROM when `options` say so, and checks its
    /// calibration.
    pub(crate) fn open(
        robot: &Robot,
        target: Target,
        options: ConnectOptions,
    ) -> Result<Connection, Error> {
        let ports = match target {
            Target::RobotFile => resolve(robot, &[])?,
            Target::Ports(p) => resolve(robot, &p)?,
            Target::VirtualSimulator | Target::Simulator => {
                return Connection::simulated(robot, target == Target::Simulator, None);
            }
        };
        let mut buses = Vec::with_capacity(ports.len());
        let mut slow = Vec::new();
        for (cfg, port) in robot.buses.iter().zip(&ports) {
            let bus = open_bus(cfg, port, Allowance::Run)?;
            if let Some(timer) = slow_adapter(bus.transport()) {
                slow.push(SlowAdapter {
                    bus: cfg.name.clone(),
                    timer,
                });
            }
            buses.push(bus);
        }
        let mut stored = Vec::new();
        for (index, (bus, port)) in buses.iter_mut().zip(ports).enumerate() {
            if options.write_servos {
                let done = store_wanted_settings(bus, robot, index, &port).map_err(|source| {
                    Error::Store {
                        bus: robot.buses[index].name.clone(),
                        port: port.clone(),
                        source: Box::new(source),
                    }
                })?;
                stored.extend(done);
            }
            prepare_bus(robot, index, bus).map_err(|refusal| Error::Refused {
                bus: robot.buses[index].name.clone(),
                port,
                refusal: Box::new(refusal),
            })?;
        }
        Ok(Connection {
            robot: robot.clone(),
            buses: Buses::Serial(buses),
            slow,
            stored,
        })
    }

    /// The built-in simulator of `robot`, paced by the wall clock or in
    /// virtual time, its shafts at `pose` (one angle per joint, in the
    /// robot file's units) or at rest.
    pub(crate) fn simulated(
        robot: &Robot,
        wall_clock: bool,
        pose: Option<&[f64]>,
    ) -> Result<Connection, Error> {
        let mut builder = SimRobot::builder(robot);
        if let Some(pose) = pose {
            builder = builder.pose(pose);
        }
        let sim = builder.build()?;
        let buses = if wall_clock {
            Buses::Wall(sim)
        } else {
            Buses::Virtual(sim)
        };
        Ok(Connection {
            robot: robot.clone(),
            buses,
            slow: Vec::new(),
            stored: Vec::new(),
        })
    }

    /// The robot connected to.
    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    /// Whether the buses are the built-in simulator's.
    pub fn is_simulated(&self) -> bool {
        !matches!(self.buses, Buses::Serial(_))
    }

    /// The buses whose FTDI adapter's latency timer slows every reply down
    /// (empty on the simulator and on other adapters).
    pub fn slow_adapters(&self) -> &[SlowAdapter] {
        &self.slow
    }

    /// What was stored in the servos' EEPROM at connect
    /// ([`ConnectOptions::write_servos`]); empty when nothing differed or
    /// nothing was asked.
    pub fn stored_settings(&self) -> &[StoredSetting] {
        &self.stored
    }

    /// The serial buses, to read or write registers between runs (`None` on
    /// the built-in simulator).
    pub fn serial_buses(&mut self) -> Option<&mut [SerialBus]> {
        match &mut self.buses {
            Buses::Serial(b) => Some(b),
            _ => None,
        }
    }

    /// The options a run takes by default on this robot (as the command
    /// line plays): the robot file's lead when it gives one, the approach
    /// to the path's start at [`APPROACH`], and [`SETTLE`] of holding the
    /// final position.
    pub fn options(&self) -> RunOptions {
        RunOptions {
            lead: self.robot.lead.map_or_else(Lead::default, Lead::Fixed),
            approach: Some(APPROACH),
            settle: SETTLE,
            ..RunOptions::default()
        }
    }

    /// Hands the buses to a run.
    pub(crate) fn into_buses(self) -> (Robot, RunBuses) {
        let clock = system_clock();
        let buses = match self.buses {
            Buses::Serial(b) => RunBuses::Serial(b),
            Buses::Virtual(sim) => RunBuses::Virtual(sim.driver_buses()),
            Buses::Wall(sim) => RunBuses::Wall(sim.wall_buses(&clock)),
        };
        (self.robot, buses)
    }
}

/// The buses a run takes, by kind.
pub(crate) enum RunBuses {
    Serial(Vec<SerialBus>),
    Virtual(Vec<servobus_driver::Bus<servobus_sim::SimBus>>),
    Wall(Vec<servobus_driver::Bus<servobus_sim::WallBus<servobus_driver::SystemClock>>>),
}

/// The options a live run takes by default on `robot` (as `servobus
/// stream`, `serve` and `follow` run it): the robot file's lead when it
/// gives one, and no approach (a live run starts where the joints are and
/// goes where its targets say).
pub fn live_options(robot: &Robot) -> RunOptions {
    RunOptions {
        lead: robot.lead.map_or_else(Lead::default, Lead::Fixed),
        approach: None,
        ..RunOptions::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn so101() -> Robot {
        let path = servobus_config::builtin::robot_path_or_name("so101".as_ref());
        servobus_config::load_robot(&path, &servobus_config::RobotOptions::default())
            .expect("the built-in arm loads")
    }

    #[test]
    fn given_ports_come_first_and_the_robot_file_gives_the_rest() {
        let mut robot = so101();
        assert_eq!(robot.buses.len(), 1, "the arm has one bus");
        robot.buses[0].port = Some("/dev/file".into());
        assert_eq!(resolve(&robot, &[]).expect("the file's"), ["/dev/file"]);
        let given = ["/dev/given".to_owned()];
        assert_eq!(resolve(&robot, &given).expect("given"), ["/dev/given"]);
    }

    #[test]
    fn a_bus_without_a_port_and_too_many_ports_are_refused() {
        let mut robot = so101();
        robot.buses[0].port = None;
        match resolve(&robot, &[]) {
            Err(Error::NoPort { bus }) => assert_eq!(bus, robot.buses[0].name),
            other => panic!("expected NoPort, got {other:?}"),
        }
        let two = ["/dev/a".to_owned(), "/dev/b".to_owned()];
        assert!(matches!(
            resolve(&robot, &two),
            Err(Error::TooManyPorts { given: 2, buses: 1 })
        ));
    }
}
