//! Robots as Python names them: a robot file, a built-in name, or YAML text.

use std::path::Path;

use servobus_config::builtin::robot_path_or_name;
use servobus_config::{load_robot as load_config, RobotOptions, RobotSource};
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

/// `robot` (as [`load_robot`] takes it) as designed: no calibration
/// applied, as `servobus calibrate` takes it.
pub(crate) fn load_design(robot: &str) -> Outcome<servobus_config::Robot> {
    let options = RobotOptions::design();
    let config = if robot.contains('\n') {
        let source = RobotSource::Text {
            name: Path::new("<text>"),
            text: robot,
        };
        load_config(source, &options)?
    } else {
        load_config(&robot_path_or_name(Path::new(robot)), &options)?
    };
    Ok(config)
}
