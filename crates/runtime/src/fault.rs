//! Faults: what was detected, where, when, and the reaction.

use std::fmt;

use serde::Serialize;

use crate::options::Reaction;

/// How far beyond a stalled joint's position its goal may go in a live
/// session, rad (1 degree).
///
/// A joint that stalls while following live targets (a gripper closing on
/// its end stop or on what it holds) is not a fault there: it is held
/// pressed, and the goal sent to its servo stays within this distance of
/// the furthest position it was measured at in the direction pushed (at a
/// stop, where it stands). A position servo's effort is its P gain times
/// its position error, so this bounds the effort: an STS3215 at its factory
/// P gain of 32 gives full torque at 50 ticks (4.4 degrees) of error, and
/// about a quarter of it at this bound, well short of its overload
/// protection. Following resumes as soon as the commanded goal comes back
/// within the bound. Status flags (heat, over-current) and a missing servo
/// still end the run.
pub const STALL_PUSH: f64 = std::f64::consts::PI / 180.0;

/// A fault the loop detected. Angles are in the report's units
/// ([`Report::units`](crate::Report::units)).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[non_exhaustive]
pub struct Fault {
    /// What happened, with the values that raised it.
    #[serde(flatten)]
    pub kind: FaultKind,
    /// The bus it happened on.
    pub bus: String,
    /// The joint concerned, if one is.
    pub joint: Option<String>,
    /// Its servo's ID.
    pub servo_id: Option<u8>,
    /// When it was detected: time since the start of the run, s.
    pub time_s: f64,
    /// The cycle of detection.
    pub cycle: u64,
    /// The reaction started in that cycle.
    pub reaction: Reaction,
    /// The angle unit of the values in `kind`.
    pub units: &'static str,
}

/// The kinds of fault, with their values.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
#[non_exhaustive]
pub enum FaultKind {
    /// The tracking error stayed beyond the tolerance.
    FollowingError {
        /// The last error (planned minus measured).
        error: f64,
        /// The tolerance.
        tolerance: f64,
        /// Consecutive readings beyond it.
        cycles: u32,
    },
    /// The joint does not follow a moving path.
    Stall {
        /// The last error.
        error: f64,
        /// The path's speed, units/s.
        planned_velocity: f64,
        /// The joint's measured speed, units/s.
        measured_velocity: f64,
        /// Consecutive stalled readings.
        cycles: u32,
    },
    /// The servo did not answer.
    Missing {
        /// Consecutive reads without a reply.
        cycles: u32,
        /// Why the last read failed.
        reason: String,
    },
    /// The servo reported error flags.
    Status {
        /// The status byte.
        flags: u8,
        /// The flags' names.
        names: String,
    },
    /// The serial port failed (unplugged adapter, closed pty).
    PortGone {
        /// The transport's message.
        message: String,
    },
}

impl fmt::Display for FaultKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FaultKind::FollowingError {
                error,
                tolerance,
                cycles,
            } => write!(
                f,
                "following error {error:.3} beyond {tolerance:.3} for {cycles} cycles"
            ),
            FaultKind::Stall {
                error,
                planned_velocity,
                measured_velocity,
                cycles,
            } => write!(
                f,
                "stalled: error {error:.3}, moving at {measured_velocity:.2}/s while the path \
                 asks {planned_velocity:.2}/s, for {cycles} cycles"
            ),
            FaultKind::Missing { cycles, reason } => {
                write!(f, "no reply for {cycles} reads ({reason})")
            }
            FaultKind::Status { flags, names } => {
                write!(f, "status flags {names} (0x{flags:02X})")
            }
            FaultKind::PortGone { message } => write!(f, "port gone: {message}"),
        }
    }
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "bus `{}`", self.bus)?;
        if let Some(joint) = &self.joint {
            write!(f, ", joint `{joint}`")?;
        }
        if let Some(id) = self.servo_id {
            write!(f, " (ID {id})")?;
        }
        write!(f, ": {}", self.kind)?;
        // The unit belongs to the angles, which only these kinds carry.
        if matches!(
            self.kind,
            FaultKind::FollowingError { .. } | FaultKind::Stall { .. }
        ) {
            write!(f, " [{}]", self.units)?;
        }
        write!(
            f,
            " at {:.3} s (cycle {}); reaction: {:?}",
            self.time_s, self.cycle, self.reaction
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fault(kind: FaultKind) -> Fault {
        Fault {
            kind,
            bus: "arm".into(),
            joint: None,
            servo_id: None,
            time_s: 1.5,
            cycle: 150,
            reaction: Reaction::Hold,
            units: "deg",
        }
    }

    #[test]
    fn the_unit_is_said_only_with_angles() {
        let gone = fault(FaultKind::PortGone {
            message: "port disconnected: end of file".into(),
        });
        assert_eq!(
            gone.to_string(),
            "bus `arm`: port gone: port disconnected: end of file at 1.500 s (cycle 150); \
             reaction: Hold"
        );
        let error = fault(FaultKind::FollowingError {
            error: 2.0,
            tolerance: 1.0,
            cycles: 3,
        });
        assert_eq!(
            error.to_string(),
            "bus `arm`: following error 2.000 beyond 1.000 for 3 cycles [deg] at 1.500 s \
             (cycle 150); reaction: Hold"
        );
    }
}
