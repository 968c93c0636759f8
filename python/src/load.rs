//! Robots as Python names them: a robot file, a built-in name, or YAML text.

use servobus_robot::Robot;

use crate::errors::Outcome;

/// Opens `robot`: YAML text when it spans several lines, else a robot file
/// or a built-in robot's name; with the calibration file `calibration`
/// instead of the one the robot names, when given.
pub(crate) fn load_robot(robot: &str, calibration: Option<&str>) -> Outcome<Robot> {
    let mut options = Robot::options();
    if let Some(path) = calibration {
        options = options.calibration(path);
    }
    if robot.contains('\n') {
        Ok(options.from_yaml(robot)?)
    } else {
        Ok(options.open(robot)?)
    }
}
