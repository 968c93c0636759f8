//! What a take captured, and the motion it becomes.

use super::{Taught, TeachError, TimedPose, STILL_DEG};
use crate::config::Robot;

/// What a take captured: the pose it started from, the pose-and-pause
/// keyframes at the times they were captured, or the recorded path.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Take {
    /// The pose the take started from (`None`: nothing was read).
    pub start: Option<Vec<f64>>,
    /// Pose-and-pause keyframes, at the time each was captured.
    pub poses: Vec<TimedPose>,
    /// The recorded path (a continuous take).
    pub samples: Vec<TimedPose>,
}

impl Take {
    /// The motion to write, if anything was captured: the recorded path
    /// reduced to keyframes that reproduce it within `tolerance_deg`
    /// degrees when `continuous` ([`Taught::continuous`]), else the
    /// keyframes at the pace they were captured ([`Taught::paced`]).
    ///
    /// # Errors
    /// [`TeachError::Unplayable`] when no timing of the recorded path plays
    /// within the joint limits.
    pub fn taught(
        &self,
        robot: &Robot,
        continuous: bool,
        tolerance_deg: f64,
    ) -> Result<Option<Taught>, TeachError> {
        let Some(start) = &self.start else {
            return Ok(None);
        };
        let deg = |d: f64| robot.units.from_rad(d.to_radians());
        if !continuous {
            return Ok(Some(Taught::paced(robot, start, &self.poses)));
        }
        if self.samples.is_empty() {
            return Ok(None);
        }
        Taught::continuous(robot, &self.samples, deg(tolerance_deg), deg(STILL_DEG)).map(Some)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{load_robot, RobotOptions, RobotSource};

    #[test]
    fn a_take_that_captured_nothing_becomes_no_motion() {
        let robot = load_robot(RobotSource::Builtin("so101"), &RobotOptions::default())
            .expect("the built-in arm");
        let empty = Take::default();
        assert_eq!(empty.taught(&robot, false, 1.0).ok(), Some(None));
        assert_eq!(empty.taught(&robot, true, 1.0).ok(), Some(None));
        // Started, but the path recorded nothing.
        let started = Take {
            start: Some(vec![0.0; 6]),
            ..Take::default()
        };
        assert_eq!(started.taught(&robot, true, 1.0).ok(), Some(None));
        // Pose and pause from a start pose: the start is the first keyframe.
        let paced = started.taught(&robot, false, 1.0).ok().flatten();
        let keyframes = paced.map(|t| t.keyframes.len());
        assert_eq!(keyframes, Some(1));
    }
}
