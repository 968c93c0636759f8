//! Wheel joints (`mode: wheel`) and a joint's `servo:` settings: what loads,
//! the register writes it makes, and what is refused, where and why.

use std::path::Path;

use servobus_config::{load_robot, ConfigError, JointConfig, Robot, RobotOptions, RobotSource};

use crate::common;

/// A one-bus robot in `units`: a position joint `arm` (ID 1), then the
/// joint `w` (ID 2) whose lines after `id:` are `rest`, each indented by 8.
fn robot_text(units: &str, rest: &[&str]) -> String {
    let mut text = format!(
        "name: r\nunits: {units}\nbuses:\n  - name: b\n    joints:\n      - name: arm\n        \
         id: 1\n        model: sts3215\n        min: -90\n        max: 90\n        \
         max_velocity: 180\n        max_acceleration: 900\n      - name: w\n        id: 2\n"
    );
    for line in rest {
        text.push_str("        ");
        text.push_str(line);
        text.push('\n');
    }
    text
}

/// A wheel `w` on an STS3215 with `extra` lines, in degrees.
fn wheel(extra: &[&str]) -> String {
    let mut lines = vec![
        "model: sts3215",
        "mode: wheel",
        "max_velocity: 250",
        "max_acceleration: 500",
    ];
    lines.extend_from_slice(extra);
    robot_text("deg", &lines)
}

/// A position joint `w` on `model` with `extra` lines, in degrees.
fn position(model: &str, extra: &[&str]) -> String {
    let model = format!("model: {model}");
    let mut lines = vec![
        model.as_str(),
        "min: -90",
        "max: 90",
        "max_velocity: 100",
        "max_acceleration: 400",
    ];
    lines.extend_from_slice(extra);
    robot_text("deg", &lines)
}

fn load(text: &str) -> Result<Robot, ConfigError> {
    let source = RobotSource::Text {
        name: Path::new("<text>"),
        text,
    };
    load_robot(source, &RobotOptions::default())
}

fn joint_w(text: &str) -> JointConfig {
    let robot = load(text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    robot.joint("w").expect("joint w").clone()
}

/// The error of `text`, which must be refused at `line`:`column` (1-based),
/// `field`, with a reason holding every one of `words`.
fn refused(text: &str, (line, column): (usize, usize), field: &str, words: &[&str]) {
    let e = load(text).expect_err(text);
    let message = e.to_string();
    let prefix = format!("<text>:{line}:{column}: {field}: ");
    assert!(
        message.starts_with(&prefix),
        "`{message}`, expected `{prefix}`"
    );
    for w in words {
        assert!(message.contains(w), "`{message}` does not say `{w}`");
    }
    assert!(!message.contains('\n'), "one line: {message}");
}

/// The `(register, raw, eeprom)` writes of `servo` on a position joint of
/// `model`.
fn writes(model: &str, servo: &str) -> Vec<(&'static str, u32, bool)> {
    let line = format!("servo: {servo}");
    let j = joint_w(&position(model, &[line.as_str()]));
    j.servo_writes()
        .iter()
        .map(|w| (w.register.name, w.raw, w.eeprom))
        .collect()
}

#[test]
fn a_wheel_loads_with_its_speed_limits_and_no_positions() {
    let j = joint_w(&wheel(&["inverted: true", "max_jerk: 5000"]));
    assert!(j.is_wheel());
    assert_eq!((j.min, j.max), (0.0, 0.0));
    assert_eq!((j.max_velocity, j.max_acceleration), (250.0, 500.0));
    assert_eq!(j.max_jerk, Some(5000.0));
    assert!(j.inverted);
    assert_eq!((j.offset, j.home), (0.0, None));
    // The position joint beside it is untouched, and says so.
    let robot = load(&wheel(&[])).expect("loads");
    let arm = robot.joint("arm").expect("arm");
    assert!(!arm.is_wheel());
    assert_eq!((arm.min, arm.max), (-90.0, 90.0));
    // `mode: position` is the default written out.
    let explicit = joint_w(&position("sts3215", &["mode: position"]));
    assert_eq!(explicit, joint_w(&position("sts3215", &[])));
}

#[test]
fn a_wheel_given_a_position_field_is_refused_naming_the_joint() {
    // Joint `w` starts at line 13; the wheel's own lines are 15 to 18, so
    // the extra line is line 19 (columns of the value, 1-based).
    for (field, value, column) in [
        ("min", "min: -10", 14),
        ("max", "max: 10", 14),
        ("home", "home: 0", 15),
        ("offset", "offset: 5", 17),
    ] {
        refused(
            &wheel(&[value]),
            (19, column),
            &format!("buses[0].joints[1].{field}"),
            &[
                "joint `w` is a wheel",
                "turns without end",
                "its target is a speed",
                &format!("`{field}:`"),
            ],
        );
    }
}

/// `text` without the line `line` of joint `w` (the joints before it keep
/// theirs).
fn without_in_w(text: &str, line: &str) -> String {
    let at = text.find("- name: w").expect("joint w");
    let (head, tail) = text.split_at(at);
    let cut = tail.replacen(&format!("        {line}\n"), "", 1);
    assert_ne!(cut, tail, "`{line}` is not a line of joint w");
    format!("{head}{cut}")
}

#[test]
fn a_position_joint_without_a_limit_is_refused_where_serde_would_say_so() {
    let full = position("sts3215", &[]);
    for (line, missing, what) in [("max: 90", "max", "highest"), ("min: -90", "min", "lowest")] {
        // At the start of joint `w`'s mapping (line 13, column 9).
        refused(
            &without_in_w(&full, line),
            (13, 9),
            "buses[0].joints[1]",
            &[
                &format!("missing field `{missing}`"),
                "joint `w` is a position joint",
                what,
                "mode: wheel",
            ],
        );
    }
    // The same place and words as a field serde itself finds missing.
    refused(
        &without_in_w(&full, "max_velocity: 100"),
        (13, 9),
        "buses[0].joints[1]",
        &["missing field `max_velocity`"],
    );
}

#[test]
fn a_wheel_faster_than_its_model_is_refused_with_both_speeds() {
    // An STS3215 turns at 3400 steps/s: 3400 x 360 / 4096 = 298.8 deg/s.
    let fast = wheel(&[]).replacen("max_velocity: 250", "max_velocity: 400", 1);
    refused(
        &fast,
        (17, 23),
        "buses[0].joints[1].max_velocity",
        &[
            "joint `w` is a wheel",
            "400 deg/s",
            "298.8 deg/s",
            "STS3215",
        ],
    );
    // At the top speed exactly it loads; in radians the top is 5.215 rad/s.
    let top = 3400.0 * 360.0 / 4096.0;
    let at_top = wheel(&[]).replacen("max_velocity: 250", &format!("max_velocity: {top}"), 1);
    assert_eq!(joint_w(&at_top).max_velocity, top);
    let rad = robot_text(
        "rad",
        &[
            "model: sts3215",
            "mode: wheel",
            "max_velocity: 5.3",
            "max_acceleration: 10",
        ],
    )
    .replace("min: -90", "min: -1.5")
    .replace("max: 90", "max: 1.5")
    .replace("max_velocity: 180", "max_velocity: 3")
    .replace("max_acceleration: 900", "max_acceleration: 15");
    refused(
        &rad,
        (17, 23),
        "buses[0].joints[1].max_velocity",
        &["5.3 rad/s", "5.2 rad/s"],
    );
}

#[test]
fn a_wheel_needs_a_model_with_a_speed_mode() {
    // The SCS series' table has no `mode` register.
    let text = wheel(&[]).replacen(
        "model: sts3215\n        mode",
        "model: scs0009\n        mode",
        1,
    );
    refused(
        &text,
        (16, 15),
        "buses[0].joints[1].mode",
        &[
            "joint `w` is a wheel",
            "SCS0009",
            "`mode` register",
            "STS3215",
        ],
    );
    let unknown = wheel(&[]).replacen("mode: wheel", "mode: spin", 1);
    refused(
        &unknown,
        (16, 15),
        "buses[0].joints[1].mode",
        &["unknown variant `spin`", "position", "wheel"],
    );
}

#[test]
fn servo_settings_become_the_registers_and_raw_values() {
    let all = "{p: 32, d: 32, i: 0, torque_limit: 80, protection_current: 1500, \
               acceleration: 2000, max_temperature: 65}";
    assert_eq!(
        writes("sts3215", all),
        [
            ("p_coefficient", 32, true),
            ("d_coefficient", 32, true),
            ("i_coefficient", 0, true),
            // 80 % in steps of 0.1 %.
            ("torque_limit", 800, false),
            // 1500 mA / 6.5 mA = 230.8.
            ("protection_current", 231, true),
            // 2000 deg/s^2 x 4096 / 360 = 22755.6 steps/s^2, in 100s.
            ("acceleration", 228, false),
            ("max_temperature", 65, true),
        ]
    );
    // Only what is given is written, and the registers are the model's.
    let j = joint_w(&position("sts3215", &["servo: {p: 16}"]));
    let settings = j.servo.as_ref().expect("settings");
    assert_eq!(
        (settings.p, settings.d, settings.torque_limit),
        (Some(16), None, None)
    );
    let [w] = j.servo_writes() else {
        panic!("one write: {:?}", j.servo_writes());
    };
    assert_eq!((w.setting, w.register.address, w.raw), ("p", 21, 16));
    assert!(joint_w(&position("sts3215", &["servo: {}"]))
        .servo_writes()
        .is_empty());
    assert_eq!(joint_w(&position("sts3215", &[])).servo, None);
    // A wheel takes them too, as a block mapping.
    let j = joint_w(&wheel(&[
        "servo:",
        "  torque_limit: 50.5",
        "  acceleration: 100",
    ]));
    let raws: Vec<u32> = j.servo_writes().iter().map(|w| w.raw).collect();
    // 100 deg/s^2 = 1137.8 steps/s^2: 11.
    assert_eq!(raws, [505, 11]);
}

#[test]
fn every_percent_and_acceleration_lands_on_the_nearest_register_step() {
    // Every tenth of a percent: the raw value is that many tenths.
    for tenths in 0..=1000u32 {
        let percent = f64::from(tenths) / 10.0;
        let got = writes("sts3215", &format!("{{torque_limit: {percent}}}"));
        assert_eq!(got, [("torque_limit", tenths, false)], "{percent} %");
    }
    // Accelerations across the register's range: the raw value is within
    // half a step (100 steps/s^2) of the acceleration asked for.
    let steps_per_deg = 4096.0 / 360.0;
    for k in 1..=200 {
        let a = f64::from(k) * 11.0;
        let got = writes("sts3215", &format!("{{acceleration: {a}}}"));
        let [(name, raw, false)] = got[..] else {
            panic!("{a}: {got:?}");
        };
        assert_eq!(name, "acceleration");
        assert!((1..=254).contains(&raw), "{a}: {raw}");
        let asked = a * steps_per_deg / 100.0;
        assert!(
            (f64::from(raw) - asked).abs() <= 0.5 + 1e-9,
            "{a}: {raw} vs {asked}"
        );
    }
}

#[test]
fn servo_values_out_of_range_are_refused_at_their_place() {
    // `servo:` is line 20, its value at column 16; each key's value follows.
    let cases: [(&str, usize, &str, &[&str]); 9] = [
        (
            "{p: 300}",
            20,
            "p",
            &["joint `w`", "from 0 to 254, got 300"],
        ),
        ("{d: -1}", 20, "d", &["from 0 to 254, got -1"]),
        ("{i: 255}", 20, "i", &["from 0 to 254, got 255"]),
        (
            "{torque_limit: 120}",
            31,
            "torque_limit",
            &["from 0 to 100, got 120"],
        ),
        (
            "{torque_limit: -5}",
            31,
            "torque_limit",
            &["from 0 to 100, got -5"],
        ),
        (
            "{acceleration: 0}",
            31,
            "acceleration",
            &["0 tells the servo to accelerate without limit", "deg/s^2"],
        ),
        (
            "{acceleration: -100}",
            31,
            "acceleration",
            &["got -100", "2232.4 deg/s^2"],
        ),
        (
            "{acceleration: 3000}",
            31,
            "acceleration",
            &["2232.4 deg/s^2", "got 3000"],
        ),
        (
            "{protection_current: -5}",
            37,
            "protection_current",
            &["current in mA", "6.5 mA", "got -5"],
        ),
    ];
    for (servo, column, key, words) in cases {
        let line = format!("servo: {servo}");
        refused(
            &position("sts3215", &[line.as_str()]),
            (20, column),
            &format!("buses[0].joints[1].servo.{key}"),
            words,
        );
    }
}

#[test]
fn the_lowest_figures_the_messages_give_are_accepted() {
    // One acceleration step is 100 steps/s^2 = 8.79 deg/s^2: half of it
    // rounds up to the first step; the message says 4.40.
    let low = position("sts3215", &["servo: {acceleration: 4.3}"]);
    refused(
        &low,
        (20, 31),
        "buses[0].joints[1].servo.acceleration",
        &["from 4.40 to 2232.4 deg/s^2"],
    );
    assert_eq!(
        writes("sts3215", "{acceleration: 4.40}"),
        [("acceleration", 1, false)]
    );
    assert_eq!(
        writes("sts3215", "{acceleration: 2232.4}"),
        [("acceleration", 254, false)]
    );
    // Half of 6.5 mA rounds up to the first step; 3.2 mA rounds to none.
    refused(
        &position("sts3215", &["servo: {protection_current: 3.2}"]),
        (20, 37),
        "buses[0].joints[1].servo.protection_current",
        &["from 3.25 to 425977"],
    );
    assert_eq!(
        writes("sts3215", "{protection_current: 3.25}"),
        [("protection_current", 1, true)]
    );
}

#[test]
fn an_unknown_servo_setting_is_refused_with_the_known_ones() {
    refused(
        &position("sts3215", &["servo: {p: 32, gain: 4}"]),
        (20, 24),
        "buses[0].joints[1].servo",
        &["unknown field `gain`", "torque_limit", "protection_current"],
    );
    refused(
        &position("sts3215", &["servo: {p: 3.5}"]),
        (20, 20),
        "buses[0].joints[1].servo.p",
        &["invalid type"],
    );
}

#[test]
fn a_setting_the_model_has_no_register_for_is_refused_naming_it() {
    // The SCS series' table has no `protection_current` or `torque_limit`.
    for key in ["protection_current", "torque_limit"] {
        let line = format!("servo: {{{key}: 50}}");
        refused(
            &position("scs0009", &[line.as_str()]),
            (20, 19 + key.len()),
            &format!("buses[0].joints[1].servo.{key}"),
            &["joint `w`", "the SCS0009 has no register", key],
        );
    }
    // Its `acceleration` states no unit, so no figure can be converted.
    refused(
        &position("scs0009", &["servo: {acceleration: 100}"]),
        (20, 31),
        "buses[0].joints[1].servo.acceleration",
        &["joint `w`", "SCS0009", "states no unit"],
    );
    // Its gains are plain numbers, as the STS series'.
    assert_eq!(writes("scs0009", "{p: 15}"), [("p_coefficient", 15, true)]);
}

#[test]
fn the_shipped_robots_have_wheels_only_on_lekiwi_and_no_servo_settings() {
    let dir = common::config("robots");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).expect("configs/robots") {
        let path = entry.expect("an entry").path();
        if path.extension().is_none_or(|e| e != "yaml") {
            continue;
        }
        let robot = load_robot(&path, &RobotOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        for j in robot.joints() {
            let wheel = robot.name == "lekiwi" && j.name.starts_with("wheel_");
            assert_eq!(j.is_wheel(), wheel, "{}: {}", path.display(), j.name);
            assert_eq!(j.servo, None, "{}: {}", path.display(), j.name);
            assert!(wheel || j.min < j.max, "{}: {}", path.display(), j.name);
        }
        // Only a robot with wheels has a base, and lekiwi's drives all three.
        assert_eq!(
            robot.base.as_ref().map(|b| b.wheels().len()),
            (robot.name == "lekiwi").then_some(3),
            "{}",
            path.display()
        );
        seen += 1;
    }
    assert!(seen >= 4, "{seen} robot files in {}", dir.display());
}

/// A base robot: an arm joint and three omni wheels, `base:` as given.
fn omni_robot(base: &str, third_mode: &str) -> String {
    let wheel = |name: &str, id: u8, mode: &str| {
        format!(
            "      - {{name: {name}, id: {id}, model: sts3215, mode: {mode}, max_velocity: 250, \
             max_acceleration: 500}}\n"
        )
    };
    let third = if third_mode == "wheel" {
        wheel("w3", 9, "wheel")
    } else {
        "      - {name: w3, id: 9, model: sts3215, min: -90, max: 90, max_velocity: 100, \
         max_acceleration: 400}\n"
            .to_string()
    };
    format!(
        "name: kiwi\nunits: deg\nbuses:\n  - name: b\n    joints:\n      - {{name: arm, id: 1, \
         model: sts3215, min: -90, max: 90, max_velocity: 100, max_acceleration: 400}}\n{}{}{}{base}",
        wheel("w1", 7, "wheel"),
        wheel("w2", 8, "wheel"),
        third
    )
}

const OMNI: &str = "base:\n  omni3:\n    wheel_radius_mm: 50\n    base_radius_mm: 125\n    \
                    wheels:\n      - {joint: w1, angle_deg: 90}\n      - {joint: w2, angle_deg: 210}\n      \
                    - {joint: w3, angle_deg: 330}\n";

#[test]
fn a_base_of_wheel_joints_loads_with_its_wheels_in_the_robots_order() {
    let robot = load(&omni_robot(OMNI, "wheel")).expect("a base robot loads");
    let base = robot.base.as_ref().expect("the base");
    assert_eq!(base.wheels(), &[1, 2, 3]);
    // Spinning in place at 1 rad/s: every wheel's rim at 0.125 m/s.
    let mut w = [0.0; 3];
    base.wheel_speeds(
        &servobus_kinematics::Twist {
            x: 0.0,
            y: 0.0,
            theta: 1.0,
        },
        &mut w,
    )
    .expect("wheel speeds");
    assert!(w.iter().all(|s| (s - 2.5).abs() < 1e-9), "{w:?}");
}

#[test]
fn a_base_on_a_position_joint_or_an_unknown_joint_is_refused_by_name() {
    let e = load(&omni_robot(OMNI, "position")).expect_err("w3 is no wheel");
    let text = e.to_string();
    assert!(
        text.contains("`w3`") && text.contains("mode: wheel"),
        "{text}"
    );
    let e = load(&omni_robot(&OMNI.replace("w2", "w9"), "wheel")).expect_err("no w9");
    let text = e.to_string();
    assert!(text.contains("w9") && text.contains("wheels[1]"), "{text}");
}
