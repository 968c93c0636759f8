//! Why a run could not start or failed as a whole.

use servobus_driver::BusError;

/// Why a run could not start, or ended abnormally. Faults detected while
/// running are not errors: they end the run normally, with their reaction,
/// and are in the [`Report`](crate::Report).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// The robot, buses and path do not fit together.
    #[error("invalid run: {0}")]
    Invalid(String),
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
    /// Planning a transition failed (approach, replace).
    #[error("cannot plan the {what}: {source}")]
    Trajectory {
        /// Which transition.
        what: &'static str,
        /// The planner's reason.
        source: servobus_trajectory::PlanError,
    },
    /// A bus thread could not be started or panicked.
    #[error("bus thread: {0}")]
    Thread(String),
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
