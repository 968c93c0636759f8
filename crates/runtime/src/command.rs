//! Commands a running loop accepts, over a bounded channel.

use std::sync::Arc;

use servobus_trajectory::Trajectory;

/// A command to a running loop. It takes effect at the start of a cycle,
/// the same on every bus and in both runners:
/// [`COMMAND_DELAY_CYCLES`](crate::COMMAND_DELAY_CYCLES) after the cycle
/// that receives it, or the cycle it was stamped with
/// ([`CommandSender::send_at`](crate::CommandSender::send_at)). Every change
/// of motion it causes is continuous in position and velocity.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub enum Command {
    /// Start the path when the run was started without
    /// [`autoplay`](crate::RunOptions::autoplay); same as
    /// [`Command::Resume`] when paused.
    Play,
    /// Slow the path's time down to a standstill along the path (a smooth
    /// ramp of the time scale, sized from the joints' velocity and
    /// acceleration limits); the joints hold on the path.
    Pause,
    /// Ramp the path's time back up to full speed.
    Resume,
    /// Stop every joint along a jerk-limited path from its commanded state,
    /// hold, and end the run.
    Stop,
    /// Disable torque on every servo now and end the run.
    TorqueOff,
    /// Replace the path: a jerk-limited transition from the commanded state
    /// to the new path's start, then the new path. Its joints are the
    /// robot's, in the robot's joint order, in radians.
    Replace(Arc<Trajectory>),
}

impl Command {
    /// [`Command::Replace`] with `trajectory`.
    pub fn replace(trajectory: Trajectory) -> Command {
        Command::Replace(Arc::new(trajectory))
    }
}
