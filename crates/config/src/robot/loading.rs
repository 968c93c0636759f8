//! Reading a robot file with its calibration: the steps of
//! [`load_robot`](super::load_robot).

use std::path::{Path, PathBuf};

use super::raw::RawRobot;
use super::{check_rate, check_servo_range, validate, Robot, RobotCalibration};
use crate::error::{ConfigError, Source};
use crate::locate::FieldPath;

/// Refuses a robot whose robot file (`source`) names a calibration file
/// that does not exist.
pub(crate) fn require_calibration(robot: &Robot, source: &Source) -> Result<(), ConfigError> {
    let RobotCalibration::Missing(file) = &robot.calibration else {
        return Ok(());
    };
    Err(source.error(
        &FieldPath::root().key("calibration"),
        format!(
            "the calibration file {} does not exist; motions are planned and played within \
             the calibrated limits: calibrate first, on the robot's servos \
             (`servobus calibrate --robot {} --port <PORT> -o {}`), \
             or remove `calibration:` to use the robot as designed",
            file.display(),
            source.path.display(),
            file.display()
        ),
    ))
}

/// Loads a robot file and applies its calibration (or `calibration`, which
/// takes precedence over the file's `calibration:`).
pub(crate) fn load_calibrated(
    path: &Path,
    calibration: Option<&Path>,
) -> Result<(Robot, Source), ConfigError> {
    let (robot, source, named) = load_design(path)?;
    with_calibration(robot, source, named, calibration)
}

/// `robot` with `calibration` applied, or else the file it `named`.
pub(super) fn with_calibration(
    robot: Robot,
    source: Source,
    named: Option<PathBuf>,
    calibration: Option<&Path>,
) -> Result<(Robot, Source), ConfigError> {
    let robot = match calibration.map(Path::to_owned).or(named) {
        Some(file) if calibration.is_some() || file.exists() => {
            crate::calibrated::apply(robot, &file)?
        }
        Some(file) => Robot {
            calibration: RobotCalibration::Missing(file),
            ..robot
        },
        None => robot,
    };
    Ok((robot, source))
}

/// `robot` when its default rate fits every bus (its file's `rate:`).
pub(super) fn rate_fits(robot: Robot, source: &Source) -> Result<Robot, ConfigError> {
    check_rate(
        &robot,
        source,
        robot.rate_hz,
        &FieldPath::root().key("rate"),
    )?;
    Ok(robot)
}

pub(super) fn load_design(path: &Path) -> Result<(Robot, Source, Option<PathBuf>), ConfigError> {
    let source = Source::read(path)?;
    design_of(source, path.parent().unwrap_or(Path::new("")))
}

/// The robot as designed in `source`, and the calibration file it names
/// (relative to `dir`, as is a URDF its `kinematics:` names).
pub(super) fn design_of(
    source: Source,
    dir: &Path,
) -> Result<(Robot, Source, Option<PathBuf>), ConfigError> {
    let raw: RawRobot = source.parse()?;
    let named = raw.calibration.as_ref().map(|rel| dir.join(rel));
    let robot = validate::robot(raw, &source, dir)?;
    check_servo_range(&robot, &source)?;
    Ok((robot, source, named))
}
