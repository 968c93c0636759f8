//! The one robot loader, from each source and with each option.

use std::path::{Path, PathBuf};

use super::*;
use crate::{builtin_path, ConfigError};

/// A one-joint robot at `rate` Hz on a 1 Mbaud bus, naming the
/// calibration file `calibration` when given.
fn text(rate: u32, calibration: Option<&str>) -> String {
    let named = calibration.map_or(String::new(), |f| format!("calibration: {f}\n"));
    format!(
        "name: one\nunits: deg\nrate: {rate}\n{named}buses:\n  - name: b\n    baud: 1000000\n    \
         latency_us: 0\n    return_delay_us: 0\n    joints:\n      - name: pan\n        id: 1\n        \
         model: scs0009\n        min: -90\n        max: 90\n        max_velocity: 100\n        \
         max_acceleration: 500\n"
    )
}

fn from_text<'a>(text: &'a str) -> RobotSource<'a> {
    RobotSource::Text {
        name: Path::new("<text>"),
        text,
    }
}

#[test]
fn a_builtin_name_loads_the_builtin_file() {
    let by_name = load_robot(RobotSource::Builtin("so101"), &RobotOptions::default());
    let by_name = by_name.expect("the built-in so101 loads by name");
    let with_suffix = load_robot(RobotSource::Builtin("so101.yaml"), &RobotOptions::default());
    assert_eq!(with_suffix.ok().as_ref(), Some(&by_name));
    assert_eq!(by_name.name, "so101");
    assert_eq!(by_name.path, PathBuf::from("<built-in>/robots/so101.yaml"));
    assert_eq!(by_name.joint_count(), 6);
    let by_path = load_robot(&builtin_path("robots/so101.yaml"), &RobotOptions::default());
    assert_eq!(by_path.ok(), Some(by_name));
}

#[test]
fn an_unknown_builtin_name_is_a_read_error() {
    let e = load_robot(
        RobotSource::Builtin("no-such-arm"),
        &RobotOptions::default(),
    );
    match e {
        Err(ConfigError::Read { path, .. }) => {
            assert_eq!(path, PathBuf::from("<built-in>/robots/no-such-arm.yaml"));
        }
        other => panic!("expected a read error, got {other:?}"),
    }
}

#[test]
fn a_text_is_named_in_its_errors_and_the_rate_check_is_an_option() {
    let fits = text(100, None);
    let robot = load_robot(from_text(&fits), &RobotOptions::default()).expect("fits");
    assert_eq!(robot.path, PathBuf::from("<text>"));
    assert_eq!(robot.rate_hz, 100.0);
    assert_eq!(robot.calibration, RobotCalibration::None);

    // 10 kHz leaves 100 us a cycle: a write and a read of one servo at
    // 1 Mbaud take more than 200 us (over 20 bytes at 10 us each).
    let fast = text(10_000, None);
    let e = load_robot(from_text(&fast), &RobotOptions::default()).expect_err("too fast");
    assert!(e.to_string().starts_with("<text>:3:7: rate:"), "{e}");
    let any = load_robot(from_text(&fast), &RobotOptions::default().any_rate()).expect("any rate");
    assert_eq!(any.rate_hz, 10_000.0);

    let broken = "name: one\nunits: deg\nrate: 100\nbuses: 7\n";
    let e = load_robot(from_text(broken), &RobotOptions::default()).expect_err("no buses");
    assert!(e.to_string().starts_with("<text>:4:"), "{e}");
}

/// A calibration file that does not exist, as a robot file names it.
const ABSENT: &str = "/nonexistent/servobus-test/one.calibration.yaml";

/// The one-joint robot naming [`ABSENT`], loaded with `options`, whose
/// calibration must be `expected` of that file; its text.
fn naming_absent(options: &RobotOptions, expected: fn(PathBuf) -> RobotCalibration) -> String {
    let named = text(100, Some(ABSENT));
    let robot = load_robot(from_text(&named), options).expect("loads");
    assert_eq!(robot.calibration.file(), Some(Path::new(ABSENT)));
    assert_eq!(robot.calibration, expected(PathBuf::from(ABSENT)));
    named
}

#[test]
fn a_named_calibration_that_does_not_exist_is_missing_and_refused_to_play() {
    let named = naming_absent(&RobotOptions::default(), RobotCalibration::Missing);

    let e = load_robot(from_text(&named), &RobotOptions::default().to_play())
        .expect_err("a missing calibration is refused to play");
    let message = e.to_string();
    assert!(message.starts_with("<text>:4:"), "{message}");
    assert!(
        message.contains(
            "the calibration file /nonexistent/servobus-test/one.calibration.yaml does not exist"
        ),
        "{message}"
    );
}

#[test]
fn a_design_load_keeps_the_named_file_unapplied() {
    let named = naming_absent(&RobotOptions::design(), RobotCalibration::Unapplied);
    // As designed: nothing applied, even to play.
    let to_play = RobotOptions {
        to_play: true,
        ..RobotOptions::design()
    };
    assert!(load_robot(from_text(&named), &to_play).is_ok());

    let plain = text(100, None);
    let robot = load_robot(from_text(&plain), &RobotOptions::design()).expect("loads");
    assert_eq!(robot.calibration, RobotCalibration::None);
    assert_eq!(robot.calibration.file(), None);
}

#[test]
fn a_given_calibration_file_that_cannot_be_read_is_an_error() {
    let plain = text(100, None);
    let options = RobotOptions::default().calibration(Some(Path::new("/nonexistent/cal.yaml")));
    assert_eq!(
        options.calibration,
        CalibrationChoice::File(PathBuf::from("/nonexistent/cal.yaml"))
    );
    let e = load_robot(from_text(&plain), &options).expect_err("no such calibration");
    assert!(matches!(e, ConfigError::Read { .. }), "{e:?}");
}
