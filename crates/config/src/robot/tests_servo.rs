//! Wheel joints and `servo:` settings, on the crate's own types.

use std::path::Path;

use servobus_protocol::registers::{SCS0009, STS3215};

use super::raw::RawServo;
use super::servo::settings;
use super::*;

fn from_text(text: &str) -> Result<Robot, crate::ConfigError> {
    let source = RobotSource::Text {
        name: Path::new("<text>"),
        text,
    };
    load_robot(source, &RobotOptions::default())
}

/// A robot with one position joint `arm` and the joint `extra` (YAML lines
/// at the joint's indentation).
fn robot(extra: &str) -> String {
    format!(
        "name: r\nbuses:\n  - name: b\n    joints:\n      - name: arm\n        id: 1\n        \
         model: sts3215\n        min: -90\n        max: 90\n        max_velocity: 180\n        \
         max_acceleration: 900\n      - name: wheel\n        id: 2\n{extra}"
    )
}

fn raw(f: impl FnOnce(&mut RawServo)) -> RawServo {
    let mut r = RawServo {
        p: None,
        d: None,
        i: None,
        torque_limit: None,
        protection_current: None,
        acceleration: None,
        max_temperature: None,
    };
    f(&mut r);
    r
}

#[test]
fn the_mode_defaults_to_position_and_a_wheel_says_so() {
    let text = robot(
        "        model: sts3215\n        mode: wheel\n        max_velocity: 200\n        \
         max_acceleration: 400\n",
    );
    let r = from_text(&text).expect("loads");
    let arm = r.joint("arm").expect("arm");
    let wheel = r.joint("wheel").expect("wheel");
    assert_eq!(arm.mode, JointMode::Position);
    assert!(!arm.is_wheel());
    assert_eq!(wheel.mode, JointMode::Wheel);
    assert!(wheel.is_wheel());
    assert_eq!((wheel.min, wheel.max, wheel.offset), (0.0, 0.0, 0.0));
    assert_eq!(wheel.rest(), 0.0);
    assert_eq!(wheel.servo, None);
    assert!(wheel.servo_writes().is_empty());
}

#[test]
fn model_limits_leave_a_wheel_at_its_files_limits() {
    let text = robot(
        "        model: sts3215\n        mode: wheel\n        max_velocity: 200\n        \
         max_acceleration: 400\n",
    );
    let r = from_text(&text).expect("loads").with_model_limits();
    let wheel = r.joint("wheel").expect("wheel");
    assert_eq!(
        (wheel.max_velocity, wheel.max_acceleration, wheel.max_jerk),
        (200.0, 400.0, None)
    );
    let (v, a) = STS3215.fastest_profile().expect("an STS profile");
    let arm = r.joint("arm").expect("arm");
    assert!((arm.max_velocity - v).abs() < 1e-9, "{}", arm.max_velocity);
    assert!((arm.max_acceleration - a).abs() < 1e-9);
}

#[test]
fn settings_keep_the_values_given_and_split_ram_from_eeprom() {
    let s = settings(
        &raw(|r| {
            r.p = Some(32);
            r.d = Some(8);
            r.i = Some(0);
            r.torque_limit = Some(80.0);
            r.protection_current = Some(1500.0);
            r.acceleration = Some(2000.0);
            r.max_temperature = Some(65);
        }),
        &STS3215,
        crate::Units::Deg,
    )
    .expect("valid settings");
    assert_eq!((s.p, s.d, s.i), (Some(32), Some(8), Some(0)));
    assert_eq!(s.torque_limit, Some(80.0));
    assert_eq!(s.protection_current, Some(1500.0));
    assert_eq!(s.acceleration, Some(2000.0));
    assert_eq!(s.max_temperature, Some(65));
    let names = |w: &mut dyn Iterator<Item = &ServoWrite>| -> Vec<&str> {
        w.map(|w| w.register.name).collect()
    };
    assert_eq!(
        names(&mut s.writes().iter()),
        [
            "p_coefficient",
            "d_coefficient",
            "i_coefficient",
            "torque_limit",
            "protection_current",
            "acceleration",
            "max_temperature"
        ]
    );
    assert_eq!(names(&mut s.ram_writes()), ["torque_limit", "acceleration"]);
    assert_eq!(
        names(&mut s.eeprom_writes()),
        [
            "p_coefficient",
            "d_coefficient",
            "i_coefficient",
            "protection_current",
            "max_temperature"
        ]
    );
    let raws: Vec<u32> = s.writes().iter().map(|w| w.raw).collect();
    // 2000 deg/s^2 = 2000 x 4096 / 360 = 22755.6 steps/s^2: 228 x 100.
    assert_eq!(raws, [32, 8, 0, 800, 231, 228, 65]);
}

#[test]
fn a_register_in_another_unit_is_refused_naming_the_setting_and_model() {
    // The SCS series' `acceleration` states no unit: no figure is made up.
    let e = settings(
        &raw(|r| r.acceleration = Some(100.0)),
        &SCS0009,
        crate::Units::Deg,
    )
    .expect_err("no unit to convert to");
    assert_eq!(e.setting, "acceleration");
    assert!(e.reason.contains("SCS0009"), "{}", e.reason);
    assert!(e.reason.contains("states no unit"), "{}", e.reason);
    // The gains are plain numbers on both series.
    let s = settings(&raw(|r| r.p = Some(20)), &SCS0009, crate::Units::Deg).expect("a gain");
    assert_eq!(s.writes()[0].register.address, 21);
}

#[test]
fn an_acceleration_in_radians_is_converted_from_radians() {
    // 40 rad/s^2 = 2291.8 deg/s^2 = 26076.2 steps/s^2: above 254 x 100.
    let e = settings(
        &raw(|r| r.acceleration = Some(40.0)),
        &STS3215,
        crate::Units::Rad,
    )
    .expect_err("too fast in rad");
    assert!(e.reason.contains("rad/s^2"), "{}", e.reason);
    // 20 rad/s^2 = 13038.1 steps/s^2: 130.
    let s = settings(
        &raw(|r| r.acceleration = Some(20.0)),
        &STS3215,
        crate::Units::Rad,
    )
    .expect("in range");
    assert_eq!(s.writes()[0].raw, 130);
}

/// Two STS3215 joints and an SCS0009 one, with `defaults` as the robot's
/// `servo_defaults:` and the first joint's own `servo:` line `own`.
fn with_defaults(defaults: &str, own: &str) -> String {
    format!(
        "name: r\nservo_defaults:\n{defaults}buses:\n  - name: b\n    joints:\n      \
         - {{name: a, id: 1, model: sts3215, min: -90, max: 90, max_velocity: 180, max_acceleration: 900{own}}}\n      \
         - {{name: b, id: 2, model: STS3215, min: -90, max: 90, max_velocity: 180, max_acceleration: 900}}\n  \
         - name: c\n    joints:\n      \
         - {{name: c, id: 3, model: scs0009, min: -90, max: 90, max_velocity: 180, max_acceleration: 900}}\n"
    )
}

#[test]
fn servo_defaults_apply_to_every_joint_of_the_model_and_a_joints_own_keys_win() {
    let r = from_text(&with_defaults(
        "  sts3215: {p: 16, torque_limit: 80}\n",
        ", servo: {torque_limit: 50}",
    ))
    .expect("loads");
    let (a, b, c) = (
        r.joint("a")
            .expect("a")
            .servo
            .as_ref()
            .expect("a's settings"),
        r.joint("b")
            .expect("b")
            .servo
            .as_ref()
            .expect("b's settings"),
        r.joint("c").expect("c"),
    );
    assert_eq!((a.p, a.torque_limit), (Some(16), Some(50.0)));
    assert_eq!((b.p, b.torque_limit), (Some(16), Some(80.0)));
    assert!(c.servo.is_none(), "another model's joint is left alone");
}

#[test]
fn a_bad_servo_default_names_its_model_and_setting() {
    let e = from_text(&with_defaults("  sts3215: {p: 300}\n", ""))
        .expect_err("p 300 is refused")
        .to_string();
    assert!(
        e.contains("servo_defaults.sts3215.p") && e.contains("model `STS3215`"),
        "{e}"
    );
    let e = from_text(&with_defaults("  sts9999: {p: 16}\n", ""))
        .expect_err("an unknown model")
        .to_string();
    assert!(
        e.contains("servo_defaults.sts9999") && e.contains("unknown model `sts9999`"),
        "{e}"
    );
    let e = from_text(&with_defaults(
        "  sts3215: {p: 16}\n  STS3215: {p: 20}\n",
        "",
    ))
    .expect_err("a model twice")
    .to_string();
    assert!(e.contains("given twice"), "{e}");
}
