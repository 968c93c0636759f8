//! The built-in simulator of a robot file: one simulated servo per joint,
//! with the bus's baud rate and return delay, its shaft at the joint's rest
//! position (or a pose you give).
//!
//! This is the one place where a robot file becomes simulated servos: the
//! command line (`servobus sim`, `play` and `bench` without `--port`), the
//! Python bindings, the examples and the tests all build their simulator
//! here (the scheduler's own tests, in `servobus-runtime`, put bare
//! servos on `servobus-sim` buses themselves).
//!
//! ```
//! use servobus_robot::config::{load_robot, RobotOptions};
//! use servobus_robot::sim::SimRobot;
//!
//! # let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/robots");
//! let robot = load_robot(&dir.join("so101.yaml"), &RobotOptions::default())?;
//! let sim = SimRobot::builder(&robot).build()?;
//! // One driver bus per robot bus, in virtual time, ready for `VirtualRun`.
//! let buses = sim.driver_buses();
//! assert_eq!(buses.len(), robot.buses.len());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::PathBuf;
use std::time::Duration;

use crate::config::{BusConfig, JointMap, Robot};
use servobus_driver::{Bus, Clock, ManualClock, Transport};
use servobus_runtime::bus_settings;
use servobus_sim::{SimBus, SimModel};

mod body;
mod served;

pub use body::{Hand, Mounting};
/// The simulated servos and buses themselves: a servo, a fault set, the
/// pseudo-terminal server other programs connect to, a bus paced by the
/// wall clock, the truth recorder, and the fastest cycle a pty can carry.
pub use servobus_sim::{
    pty_floor, FaultSpecError, Faults, FloorCycle, PtyError, PtyServer, SimServo, Truth, WallBus,
};

/// How often the truth is sampled: 100 Hz, twice the 50 Hz a reader of the
/// truth may count on.
pub const TRUTH_PERIOD: Duration = Duration::from_millis(10);

/// A truth recorder for `robot`: one column per joint, named as in the
/// robot file and in its joint order, sampled every [`TRUTH_PERIOD`]. Give
/// it to [`SimRobotBuilder::truth`].
pub fn new_truth(robot: &Robot) -> Truth {
    Truth::new(
        robot.joints().map(|j| j.name.clone()).collect(),
        TRUTH_PERIOD,
    )
}

/// Why a robot file's servos cannot be simulated.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimRobotError {
    /// The bus's baud rate is not one a servo can be set to.
    #[error("{}: bus `{bus}` runs at {baud} baud, which no Feetech servo supports", .file.display())]
    Baud {
        /// The robot file.
        file: PathBuf,
        /// The bus.
        bus: String,
        /// Its baud rate.
        baud: u32,
    },
    /// The simulator has no model of a joint's servo.
    #[error("{}: joint `{joint}`: the simulator has no model {model}", .file.display())]
    Model {
        /// The robot file.
        file: PathBuf,
        /// The joint.
        joint: String,
        /// The model's name.
        model: &'static str,
    },
    /// The robot has no bus to serve.
    #[error("{}: the robot has no bus", .file.display())]
    NoBus {
        /// The robot file.
        file: PathBuf,
    },
    /// No bus of the robot has the name asked for.
    #[error("{}: no bus named `{name}` (buses: {})", .file.display(), .buses.join(", "))]
    NoSuchBus {
        /// The robot file.
        file: PathBuf,
        /// The name asked for.
        name: String,
        /// The robot's buses, in its file's order.
        buses: Vec<String>,
    },
    /// Two joints served on one port have the same ID: the port's servos
    /// cannot both answer it.
    #[error(
        "{}: ID {id} is used by `{}` on bus `{}` and by `{}` on bus `{}`",
        .file.display(), .joints[0].1, .joints[0].0, .joints[1].1, .joints[1].0
    )]
    SharedId {
        /// The robot file.
        file: PathBuf,
        /// The ID.
        id: u8,
        /// The two joints as `(bus, joint)`, the first one found first.
        joints: Box<[(String, String); 2]>,
    },
    /// A start pose does not have one angle per joint.
    #[error("{}: a start pose of {got} angles for a robot of {want} joints", .file.display())]
    Pose {
        /// The robot file.
        file: PathBuf,
        /// Angles given.
        got: usize,
        /// Joints of the robot.
        want: usize,
    },
}

/// The servo baud-table index of `bus`'s baud rate.
///
/// # Errors
/// [`SimRobotError::Baud`] for a rate outside the servo baud table.
pub fn baud_index(robot: &Robot, bus: &BusConfig) -> Result<u8, SimRobotError> {
    servobus_protocol::registers::baud_index(bus.baud).ok_or_else(|| SimRobotError::Baud {
        file: robot.path.clone(),
        bus: bus.name.clone(),
        baud: bus.baud,
    })
}

/// The simulated servos of `bus`: each joint's servo with its ID, model, the
/// bus's return delay and baud rate, and its shaft at the joint's rest
/// position.
///
/// # Errors
/// [`SimRobotError`] when a servo cannot be simulated.
pub fn bus_servos(robot: &Robot, bus: &BusConfig) -> Result<Vec<SimServo>, SimRobotError> {
    SimRobot::builder(robot).servos(bus)
}

/// The robot's buses simulated in virtual time, ready for
/// [`VirtualRun`](servobus_runtime::VirtualRun): one [`SimBus`] per robot
/// bus, each with its own [`ManualClock`] (the runtime moves them in step)
/// and the driver settings of the robot file. Shorthand for
/// `SimRobot::builder(robot).build()?.driver_buses()`.
///
/// # Errors
/// [`SimRobotError`] when a servo cannot be simulated.
pub fn virtual_buses(robot: &Robot) -> Result<Vec<Bus<SimBus>>, SimRobotError> {
    Ok(SimRobot::builder(robot).build()?.driver_buses())
}

/// A robot file's servos on simulated buses in virtual time.
///
/// Build one with [`SimRobot::builder`]; its options give the robot a body:
///
/// ```
/// use servobus_robot::config::{load_robot, RobotOptions};
/// use servobus_robot::sim::{new_truth, Hand, Mounting, SimRobot};
///
/// # let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/robots");
/// let robot = load_robot(&dir.join("so101.yaml"), &RobotOptions::default())?;
/// let truth = new_truth(&robot);
/// // Joint 0 (shoulder_pan) turned by hand from 0 to 45 deg in the first second.
/// let hand = Hand::from_keyframes(&robot, &[(0.0, vec![(0, 0.0)]), (1.0, vec![(0, 45.0)])]);
/// let sim = SimRobot::builder(&robot)
///     .mounting(Mounting::random(&robot, 7)) // horns anywhere on the turn
///     .hand(hand)
///     .truth(&truth)
///     .build()?;
/// sim.buses()[0].clock().advance(std::time::Duration::from_secs(2));
/// sim.settle();
/// let last = truth.rows().pop().expect("rows every 10 ms");
/// assert!((last.angles_deg[0] - 45.0).abs() < 0.01);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// The [`SimBus`] handles it holds
/// share their servos with every driver bus made from them, so a test can
/// run the robot through [`SimRobot::driver_buses`] and inspect the servos
/// through [`SimRobot::buses`].
#[derive(Debug, Clone)]
pub struct SimRobot {
    buses: Vec<SimBus>,
    settings: Vec<servobus_driver::BusSettings>,
}

/// Options of a [`SimRobot`]; see [`SimRobot::builder`].
#[derive(Debug, Clone)]
pub struct SimRobotBuilder<'a> {
    robot: &'a Robot,
    pose: Option<Vec<f64>>,
    mounting: Option<Mounting>,
    hand: Option<Hand>,
    truth: Option<Truth>,
}

impl SimRobot {
    /// The options of a simulated `robot`: by default every shaft at its
    /// joint's rest position.
    pub fn builder(robot: &Robot) -> SimRobotBuilder<'_> {
        SimRobotBuilder {
            robot,
            pose: None,
            mounting: None,
            hand: None,
            truth: None,
        }
    }

    /// The simulated buses, one per robot bus, in the robot file's order.
    pub fn buses(&self) -> &[SimBus] {
        &self.buses
    }

    /// Driver buses on the simulated buses (each on its bus's own clock,
    /// with the robot file's settings), ready for
    /// [`VirtualRun`](servobus_runtime::VirtualRun).
    pub fn driver_buses(&self) -> Vec<Bus<SimBus>> {
        self.buses_on(SimBus::clone)
    }

    /// Driver buses on the simulated buses paced by the wall clock `clock`
    /// ([`WallBus`]: the servos answer in real time, in this process), with
    /// the robot file's settings, ready for [`spawn`](servobus_runtime::spawn).
    /// Give the run the same clock.
    pub fn wall_buses<C: Clock>(&self, clock: &C) -> Vec<Bus<WallBus<C>>> {
        self.buses_on(|sim| WallBus::new(sim.clone(), clock.clone()))
    }

    /// One driver bus per simulated bus, on the transport `on` makes of it
    /// (and that transport's clock), with the robot file's settings.
    fn buses_on<T: Transport>(&self, on: impl Fn(&SimBus) -> T) -> Vec<Bus<T>> {
        self.buses
            .iter()
            .zip(&self.settings)
            .map(|(sim, settings)| Bus::new(on(sim), *settings))
            .collect()
    }

    /// Steps every servo to its bus clock's time (so that the truth is
    /// recorded up to now).
    pub fn settle(&self) {
        for b in &self.buses {
            b.settle();
        }
    }
}

impl SimRobotBuilder<'_> {
    /// Mounts every servo on its joint as `mounting` says (see
    /// [`Mounting::load`], [`Mounting::random`]). Without a mounting (and
    /// without a hand or a truth recorder) the servos are bare shafts at
    /// the robot file's ticks, as before bodies existed.
    #[must_use]
    pub fn mounting(mut self, mounting: Mounting) -> Self {
        self.mounting = Some(mounting);
        self
    }

    /// Puts `hand` on the joints it names: it moves those whose torque is
    /// off and pushes on those whose torque is on. A joint whose hand path
    /// starts at time 0 starts in the hand's pose.
    #[must_use]
    pub fn hand(mut self, hand: Hand) -> Self {
        self.hand = Some(hand);
        self
    }

    /// Records every joint's physical angle into `truth` (see [`new_truth`]),
    /// into the column of the joint's name (joints it has no column for are
    /// not recorded).
    #[must_use]
    pub fn truth(mut self, truth: &Truth) -> Self {
        self.truth = Some(truth.clone());
        self
    }

    /// Every shaft at `pose` instead of the rest positions: one angle per
    /// joint in the robot's joint order, in the robot file's units.
    #[must_use]
    pub fn pose(mut self, pose: &[f64]) -> Self {
        self.pose = Some(pose.to_vec());
        self
    }

    /// The simulated robot.
    ///
    /// # Errors
    /// [`SimRobotError`] when a servo cannot be simulated or the pose does
    /// not fit the robot.
    pub fn build(self) -> Result<SimRobot, SimRobotError> {
        let robot = self.robot;
        let pose = match self.pose.clone() {
            Some(p) if p.len() != robot.joint_count() => {
                return Err(SimRobotError::Pose {
                    file: robot.path.clone(),
                    got: p.len(),
                    want: robot.joint_count(),
                })
            }
            Some(p) => p,
            None => robot.joints().map(|j| j.rest()).collect(),
        };
        let mut buses = Vec::with_capacity(robot.buses.len());
        let mut settings = Vec::with_capacity(robot.buses.len());
        for bus in &robot.buses {
            let servos = self.servos_at(bus, &pose)?;
            buses.push(SimBus::new(ManualClock::new(), bus.baud).with_servos(servos));
            settings.push(bus_settings(bus));
        }
        Ok(SimRobot { buses, settings })
    }

    /// The simulated servos of `bus` (one of the robot's buses, possibly
    /// with another baud rate, as a pty serving several buses needs) with
    /// every option of this builder, each shaft at its rest position or the
    /// builder's pose.
    ///
    /// # Errors
    /// [`SimRobotError`] when a servo cannot be simulated.
    pub fn servos(&self, bus: &BusConfig) -> Result<Vec<SimServo>, SimRobotError> {
        let pose = match &self.pose {
            Some(p) => p.clone(),
            None => self.robot.joints().map(|j| j.rest()).collect(),
        };
        self.servos_at(bus, &pose)
    }

    /// The servos of `bus` at `pose` (robot units, one angle per joint of
    /// the robot).
    fn servos_at(&self, bus: &BusConfig, pose: &[f64]) -> Result<Vec<SimServo>, SimRobotError> {
        let robot = self.robot;
        let baud = baud_index(robot, bus)?;
        let bodies = self.mounting.is_some() || self.hand.is_some() || self.truth.is_some();
        let design = Mounting::of_robot_file(robot);
        let mounting = self.mounting.as_ref().unwrap_or(&design);
        let mut servos = Vec::with_capacity(bus.joints.len());
        for joint in &bus.joints {
            let model = SimModel::by_number(joint.model.number)
                .or_else(|| SimModel::by_name(joint.model.name))
                .ok_or_else(|| SimRobotError::Model {
                    file: robot.path.clone(),
                    joint: joint.name.clone(),
                    model: joint.model.name,
                })?;
            // The joint's place in the robot (bus configs may be copies).
            let index = robot.joints().position(|j| j.name == joint.name);
            let angle = index
                .and_then(|i| pose.get(i))
                .copied()
                .unwrap_or(joint.rest());
            let mut servo = SimServo::new(model, joint.id)
                .with_return_delay(bus.return_delay)
                .with_byte(servobus_sim::addr::BAUD_RATE, baud);
            if joint.is_wheel() {
                // Set up as the robot file asks: a wheel's servo in its
                // constant-speed mode (only STS-type models have wheels).
                servo = servo.with_byte(servobus_sim::addr::MODE, joint.mode.operating_mode());
            }
            let servo = match index.filter(|_| bodies) {
                None => {
                    let map = JointMap::new(joint, robot.units);
                    servo.with_position(map.to_ticks(robot.units.to_rad(angle)))
                }
                Some(i) => self.with_body(servo, mounting, i, angle),
            };
            servos.push(servo);
        }
        Ok(servos)
    }

    /// `servo` mounted as joint `i`, with the hand and the truth recorder.
    fn with_body(&self, servo: SimServo, mounting: &Mounting, i: usize, angle: f64) -> SimServo {
        let hand = self.hand.as_ref().and_then(|h| h.path(i)).cloned();
        let mut deg = self.robot.units.to_rad(angle).to_degrees();
        if let Some(&(t, a)) = hand.as_ref().and_then(|h| h.keys().first()) {
            if t == 0.0 {
                deg = a;
            }
        }
        let mount = mounting.mounts()[i];
        let mut servo = servo.with_mount(mount, deg);
        if let Some(h) = hand {
            servo = servo.with_hand(h);
        }
        if let Some(t) = &self.truth {
            // Columns are matched by name: a recorder may hold a subset.
            let name = self.robot.joints().nth(i).map(|j| j.name.as_str());
            if let Some(col) = t.names().iter().position(|n| Some(n.as_str()) == name) {
                servo = servo.with_truth(t, col);
            }
        }
        servo
    }
}
