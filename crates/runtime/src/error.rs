//! Why a run could not start or failed as a whole.

use servobus_driver::BusError;

/// Why a run could not start, or ended abnormally. Faults detected while
/// running are not errors: they end the run normally, with their reaction,
/// and are in the [`Report`](crate::Report).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// The control rate is not a positive number of Hz.
    #[error("the rate must be a positive number of Hz, got {rate_hz} Hz")]
    Rate {
        /// The rate given.
        rate_hz: f64,
    },
    /// The live targets' timeout is not a positive time.
    #[error("the target timeout must be positive")]
    TargetTimeout,
    /// Another number of buses than the robot has.
    #[error("robot `{robot}` has {expected} buses, {given} given")]
    BusCount {
        /// The robot.
        robot: String,
        /// Its buses.
        expected: usize,
        /// The buses given.
        given: usize,
    },
    /// A path for another number of joints than the robot has.
    #[error("the path has {given} joints, robot `{robot}` {expected}")]
    JointCount {
        /// The robot.
        robot: String,
        /// Its joints.
        expected: usize,
        /// The path's joints.
        given: usize,
    },
    /// A replacing path ([`Command::Replace`](crate::Command::Replace)) for
    /// another number of joints than the robot has.
    #[error("the new path has {given} joints, the robot {expected}")]
    NewPathJoints {
        /// The robot's joints.
        expected: usize,
        /// The new path's.
        given: usize,
    },
    /// A joint's servo is of another series than its bus talks.
    #[error("bus `{bus}`: joint `{joint}` is a {model} ({joint_series:?} series) but the bus talks {bus_series:?}")]
    Series {
        /// The bus.
        bus: String,
        /// The joint.
        joint: String,
        /// Its servo's model.
        model: &'static str,
        /// The model's series.
        joint_series: servobus_protocol::registers::Series,
        /// The bus's.
        bus_series: servobus_protocol::registers::Series,
    },
    /// The series' register map lacks the goal or present position.
    #[error("the {0:?} register map has no goal or present position")]
    NoPositionRegisters(servobus_protocol::registers::Series),
    /// The rate does not fit a bus.
    #[error("bus `{bus}`: {source}")]
    Plan {
        /// The bus.
        bus: String,
        /// The planner's reason.
        source: servobus_timing::CycleError,
    },
    /// A bus failed while setting up (reading the start positions, enabling
    /// torque).
    #[error("bus `{bus}`: {what}: {source}")]
    Startup {
        /// The bus.
        bus: String,
        /// What was being done.
        what: &'static str,
        /// The bus error.
        source: BusError,
    },
    /// A servo did not answer while setting up.
    #[error("bus `{bus}`: servo {id} (joint `{joint}`) does not answer: {reason}")]
    NoServo {
        /// The bus.
        bus: String,
        /// The servo's ID.
        id: u8,
        /// Its joint.
        joint: String,
        /// Why the read failed.
        reason: String,
    },
    /// A servo's operating mode (register `mode`, 33) is not its joint's:
    /// a wheel needs mode 1 (constant speed), a position joint mode 0. The
    /// mode is an EEPROM setting, which a run writes only when asked (the
    /// facade's `ConnectOptions::write_servos`).
    #[error(
        "bus `{bus}`: joint `{joint}` (servo {id}) is in operating mode {found} ({}), \
         a {} joint needs mode {wanted} ({}): `servobus doctor --robot FILE --port PORT --fix \
         --write-servos` sets it, or `--write-servos` on the command that runs (an EEPROM \
         register, which a run writes only when asked)",
        mode_name(*found), if *wanted == 1 { "wheel" } else { "position" }, mode_name(*wanted)
    )]
    Mode {
        /// The bus.
        bus: String,
        /// The joint.
        joint: String,
        /// Its servo's ID.
        id: u8,
        /// The mode the servo is in.
        found: u8,
        /// The mode the joint needs.
        wanted: u8,
    },
    /// A servo held another value of a RAM `servo:` setting than was just
    /// written to it.
    #[error(
        "bus `{bus}`: joint `{joint}` (servo {id}): its `servo: {setting}` was written as \
         {wrote} but reads back as {held}: is the servo the model the robot file says?"
    )]
    Setting {
        /// The bus.
        bus: String,
        /// The joint.
        joint: String,
        /// Its servo's ID.
        id: u8,
        /// The `servo:` key.
        setting: &'static str,
        /// The raw value written.
        wrote: i32,
        /// The raw value read back.
        held: i32,
    },
    /// A bus with wheel joints whose register map lacks what a wheel needs
    /// (the operating mode, goal speed, or a present speed right after the
    /// present position).
    #[error(
        "bus `{bus}`: joint `{joint}` is a wheel but the {series:?} register map has no {what}"
    )]
    NoWheelRegisters {
        /// The bus.
        bus: String,
        /// The wheel joint.
        joint: String,
        /// Its series.
        series: servobus_protocol::registers::Series,
        /// The register missing.
        what: &'static str,
    },
    /// Planning a transition failed (approach, replace).
    #[error("cannot plan the {what}: {source}")]
    Trajectory {
        /// Which transition.
        what: &'static str,
        /// The planner's reason.
        source: servobus_trajectory::PlanError,
    },
    /// A thread of the run could not be started.
    #[error("cannot start a thread of the run: {0}")]
    Spawn(#[source] std::io::Error),
    /// A thread of the run panicked (`what`: which).
    #[error("{what} panicked")]
    Panicked {
        /// Which thread.
        what: &'static str,
    },
    /// The run has ended: it takes no more commands or targets.
    #[error("the run has ended")]
    Ended,
}

/// The name of operating mode `mode` (register `mode`, 33).
fn mode_name(mode: u8) -> &'static str {
    match mode {
        0 => "position",
        1 => "constant speed, a wheel",
        2 => "PWM",
        3 => "step",
        _ => "unknown",
    }
}

/// The serial port of a bus failed while running (unplugged adapter, closed
/// pty): nothing more can be sent on that bus. A servo's silence is not
/// this; it is counted and judged by tracking.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub(crate) struct PortGone(pub BusError);

impl PortGone {
    /// `Err` when `result` failed because the port is gone; a timeout or a
    /// bad reply is the servos' business, not the port's.
    pub(crate) fn check<V>(result: Result<V, BusError>) -> Result<Option<V>, PortGone> {
        match result {
            Ok(v) => Ok(Some(v)),
            Err(BusError::Transport(t)) if !t.is_timeout() => Err(PortGone(BusError::Transport(t))),
            Err(_) => Ok(None),
        }
    }
}
