//! Bad robot and motion files are refused with `file:line:column: field: reason`.

use crate::common;
#[path = "../../examples/common/config_check.rs"]
mod config_check;

use std::path::{Path, PathBuf};

use servobus_config::{load_motion, load_motion_text, load_robot, ConfigError, RobotOptions};

/// Writes `text` to a fresh file named `name` in a directory of its own.
/// The robot file at `path`, which must be valid.
fn valid(path: &Path) -> servobus_config::Robot {
    load_robot(path, &RobotOptions::default()).expect("valid")
}

fn write(dir: &str, name: &str, text: &str) -> PathBuf {
    common::temp_file(&format!("config_errors/{dir}"), name, text)
}

/// A valid two-joint robot; tests break one line of it.
const ROBOT: &str = "\
name: two
units: deg
rate: 100
buses:
  - name: bus
    baud: 1000000
    joints:
      - name: a
        id: 1
        model: sts3215
        min: -90
        max: 90
        max_velocity: 180
        max_acceleration: 900
      - name: b
        id: 2
        model: sts3215
        min: -45
        max: 45
        max_velocity: 180
        max_acceleration: 900
";

fn robot_error(test: &str, from: &str, to: &str) -> (PathBuf, ConfigError) {
    assert!(ROBOT.contains(from), "{from}");
    let p = write(test, "robot.yaml", &ROBOT.replacen(from, to, 1));
    let e = load_robot(&p, &RobotOptions::default()).expect_err("the robot must be refused");
    (p, e)
}

fn expect(e: &ConfigError, file: &Path, line: usize, column: usize, field: &str, reason: &str) {
    let text = e.to_string();
    let prefix = format!("{}:{line}:{column}: {field}: ", file.display());
    assert!(
        text.starts_with(&prefix),
        "got `{text}`, expected prefix `{prefix}`"
    );
    assert!(
        text.contains(reason),
        "got `{text}`, expected it to mention `{reason}`"
    );
    assert_eq!(e.position(), Some((line, column)));
    assert_eq!(e.field(), Some(field));
}

#[test]
fn the_valid_robot_loads() {
    let p = write("valid", "robot.yaml", ROBOT);
    let r = valid(&p);
    assert_eq!(r.joint_count(), 2);
    assert_eq!(r.path, p);
}

#[test]
fn robot_errors_name_the_file_line_column_and_field() {
    let cases = [
        // duplicate id points at the second id
        (
            "dup_id",
            "id: 2",
            "id: 1",
            (16, 13),
            "buses[0].joints[1].id",
            "ID 1 is already used on bus `bus`",
        ),
        // id out of range
        (
            "big_id",
            "id: 2",
            "id: 254",
            (16, 13),
            "buses[0].joints[1].id",
            "from 0 to 253, got 254",
        ),
        // min not below max
        (
            "minmax",
            "max: 45",
            "max: -50",
            (19, 14),
            "buses[0].joints[1].max",
            "must be greater than min",
        ),
        // limits must be positive
        (
            "vel",
            "max_velocity: 180\n        max_acceleration: 900\n      - name: b",
            "max_velocity: 0\n        max_acceleration: 900\n      - name: b",
            (13, 23),
            "buses[0].joints[0].max_velocity",
            "must be positive",
        ),
        // limit beyond the servo range
        (
            "range",
            "min: -90",
            "min: -200",
            (11, 14),
            "buses[0].joints[0].min",
            "beyond what the STS3215 can reach",
        ),
        // duplicate joint name
        (
            "name",
            "- name: b\n",
            "- name: a\n",
            (15, 15),
            "buses[0].joints[1].name",
            "joint name `a` is already used",
        ),
        // a rate the baud register cannot select names the ones it can
        // (register 6's table in the Feetech manual)
        (
            "baud",
            "baud: 1000000",
            "baud: 9600",
            (6, 11),
            "buses[0].baud",
            "9600 baud is not a rate the servos can be set to; use one of 1000000, 500000, \
             250000, 128000, 115200, 76800, 57600, 38400",
        ),
        // type errors come from serde yaml with their position
        (
            "type",
            "baud: 1000000",
            "baud: fast",
            (6, 11),
            "buses[0].baud",
            "invalid type",
        ),
        // unknown fields are refused
        (
            "unknown",
            "max_velocity: 180\n        max_acceleration: 900\n      - name: b",
            "max_velocity: 180\n        max_accel: 900\n      - name: b",
            (14, 9),
            "buses[0].joints[0]",
            "unknown field `max_accel`",
        ),
    ];
    for (test, from, to, (line, column), field, reason) in cases {
        let (p, e) = robot_error(test, from, to);
        expect(&e, &p, line, column, field, reason);
    }
}

#[test]
fn unknown_model_lists_the_known_ones() {
    let (p, e) = robot_error(
        "model",
        "model: sts3215\n        min: -45",
        "model: xl430\n        min: -45",
    );
    expect(
        &e,
        &p,
        17,
        16,
        "buses[0].joints[1].model",
        "unknown model `xl430`",
    );
    assert!(e.to_string().contains("STS3215"));
}

#[test]
fn syntax_errors_have_a_position() {
    let p = write("syntax", "robot.yaml", "name: x\nbuses: [\n");
    let e = load_robot(&p, &RobotOptions::default()).expect_err("broken YAML");
    let (line, _) = e.position().expect("located");
    assert!(line >= 2, "{e}");
    assert!(e.to_string().starts_with(&format!("{}:", p.display())));
}

#[test]
fn a_rate_the_bus_cannot_carry_says_what_fits() {
    let (p, e) = robot_error("rate", "rate: 100", "rate: 5000");
    expect(&e, &p, 3, 7, "rate", "bus `bus`: 5000 Hz cannot be met");
    // 14 + 10 + 2 x 8 bytes (400 us), 2 turnarounds of 50 us, and the
    // simulator's pty (no port: 60 us a round trip, 8 us a reply): 576 us.
    assert!(e.to_string().contains("lower the rate to 1736 Hz"), "{e}");
}

#[test]
fn a_missing_file_is_a_read_error() {
    let e = load_robot(
        Path::new("/nonexistent/robot.yaml"),
        &RobotOptions::default(),
    )
    .expect_err("missing");
    assert!(matches!(e, ConfigError::Read { .. }));
    assert_eq!(e.position(), None);
}

fn motion_error(test: &str, motion: &str) -> (PathBuf, ConfigError) {
    write(test, "robot.yaml", ROBOT);
    let p = write(test, "motion.yaml", motion);
    let e = load_motion(&p, None).expect_err("the motion must be refused");
    (p, e)
}

#[test]
fn motion_errors_name_the_file_line_column_and_field() {
    let cases = [
        // a keyframe outside a limit names the joint and limit
        (
            "kf_limit",
            "robot: robot.yaml\nkeyframes:\n  - pose: {a: 0}\n  - pose: {a: 10, b: 50}\n",
            (4, 22),
            "keyframes[1].pose.b",
            "keyframe 1: 50 deg is outside the limits of joint `b` [-45, 45]",
        ),
        // a joint the robot lacks points at its name
        (
            "kf_joint",
            "robot: robot.yaml\nkeyframes:\n  - pose: {a: 0}\n  - pose:\n      a: 10\n      elbow: 5\n",
            (6, 7),
            "keyframes[1].pose.elbow",
            "has no joint `elbow` (joints: a, b)",
        ),
        // an unknown pose name
        (
            "kf_pose",
            "robot: robot.yaml\nposes:\n  home: {a: 0}\nkeyframes:\n  - pose: home\n  - pose: hoem\n",
            (6, 11),
            "keyframes[1].pose",
            "unknown pose `hoem` (poses: home)",
        ),
        // a named pose outside a limit
        (
            "pose_limit",
            "robot: robot.yaml\nposes:\n  wide: {a: 0, b: -1}\n  bad: {b: 1.0}\nunits: rad\nkeyframes:\n  - pose: wide\n",
            (3, 19),
            "poses.wide.b",
            "-1 rad is outside the limits of joint `b`",
        ),
        // times must increase
        (
            "kf_time",
            "robot: robot.yaml\nkeyframes:\n  - {at: 0, pose: {a: 0}}\n  - {at: 2, pose: {a: 5}}\n  - {at: 1.5, pose: {a: 0}}\n",
            (5, 10),
            "keyframes[2].at",
            "1.5 s is not after keyframe 1 at 2 s",
        ),
        // the motion rate is checked against the bus
        (
            "m_rate",
            "robot: robot.yaml\nrate: 9000\nkeyframes:\n  - pose: {a: 0}\n",
            (2, 7),
            "rate",
            "bus `bus`: 9000 Hz cannot be met",
        ),
        // a repeat of zero
        (
            "repeat",
            "robot: robot.yaml\nkeyframes:\n  - pose: {a: 0}\nrepeat: 0\n",
            (4, 9),
            "repeat",
            "at least 1",
        ),
    ];
    for (test, motion, (line, column), field, reason) in cases {
        let (p, e) = motion_error(test, motion);
        expect(&e, &p, line, column, field, reason);
        // The same text given as text (a message, no file): the same error,
        // located in the text under the name it was given.
        let robot = p.with_file_name("robot.yaml");
        let name = Path::new("<motion text>");
        let e = load_motion_text(name, motion, Some(&robot), None)
            .expect_err("the motion text must be refused");
        expect(&e, name, line, column, field, reason);
    }
}

#[test]
fn a_motion_given_as_text_loads_as_its_file_does() {
    let dir = "m_text";
    let robot = write(dir, "robot.yaml", ROBOT);
    let text =
        "robot: robot.yaml\nkeyframes:\n  - pose: {a: 0}\n  - {at: 1, pose: {a: 20, b: -10}}\n";
    let file = write(dir, "motion.yaml", text);
    let (from_file, _) = load_motion(&file, None).expect("the file loads");
    let (from_text, r) =
        load_motion_text(Path::new("<text>"), text, Some(&robot), None).expect("the text loads");
    assert_eq!(from_text.keyframes, from_file.keyframes);
    assert_eq!(from_text.path, Path::new("<text>"));
    assert_eq!(r.name, "two");
    // Longer than a motion file may be: refused before it is parsed.
    let huge = format!("robot: robot.yaml\n#{}\n", "x".repeat(2 << 20));
    let e =
        load_motion_text(Path::new("<text>"), &huge, Some(&robot), None).expect_err("too large");
    assert!(matches!(e, ConfigError::TooLarge { .. }), "{e}");
}

#[test]
fn errors_in_the_robot_name_the_robot_file() {
    let dir = "m_robot";
    let r = write(dir, "robot.yaml", &ROBOT.replacen("id: 2", "id: 1", 1));
    let p = write(
        dir,
        "motion.yaml",
        "robot: robot.yaml\nkeyframes:\n  - pose: {a: 0}\n",
    );
    let e = load_motion(&p, None).expect_err("bad robot");
    expect(&e, &r, 16, 13, "buses[0].joints[1].id", "already used");
}

#[test]
fn a_motion_without_robot_asks_for_one() {
    let (p, e) = motion_error("no_robot", "keyframes:\n  - pose: {a: 0}\n");
    assert!(
        e.to_string().starts_with(&format!("{}:1:1: ", p.display())),
        "{e}"
    );
    // In the file's terms: the library names no command-line flag.
    assert!(e.to_string().contains("add `robot: FILE`"), "{e}");
    assert!(!e.to_string().contains("--"), "{e}");
}

#[test]
fn the_lag_compensation_lead_is_read_and_checked() {
    let r = valid(&write("no_lead", "robot.yaml", ROBOT));
    assert_eq!(r.lead, None, "absent: identified at run time");
    let p = write(
        "lead",
        "robot.yaml",
        &ROBOT.replacen("rate: 100", "rate: 100\nlead_ms: 12.5", 1),
    );
    let r = valid(&p);
    assert_eq!(r.lead, Some(std::time::Duration::from_micros(12_500)));
    let (p, e) = robot_error("bad_lead", "rate: 100", "rate: 100\nlead_ms: -3");
    expect(
        &e,
        &p,
        4,
        10,
        "lead_ms",
        "must be between 0 and 500 ms, got -3",
    );
}

#[test]
fn busy_polling_is_off_unless_the_robot_file_asks() {
    let r = valid(&write("no_busy", "robot.yaml", ROBOT));
    assert!(r.buses.iter().all(|b| !b.busy_poll));
    let p = write(
        "busy",
        "robot.yaml",
        &ROBOT.replacen("baud: 1000000", "baud: 1000000\n    busy_poll: true", 1),
    );
    let r = valid(&p);
    assert!(r.buses[0].busy_poll);
}

/// The YAML fuzzers' kept inputs (`testdata/fuzz-config/`) pass every
/// check again; the hand-made seeds are refused by every loader.
#[test]
fn the_fuzzers_kept_inputs_are_refused_cleanly() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let workspace = config_check::Workspace::new(&repo).expect("a scratch directory");
    let dir = repo.join("testdata/fuzz-config");
    let mut seeds = 0;
    for entry in std::fs::read_dir(&dir).expect("testdata/fuzz-config") {
        let path = entry.expect("a directory entry").path();
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
        let Some(name) = name.filter(|n| !n.ends_with(".md")) else {
            continue;
        };
        let input = std::fs::read(&path).expect("a kept input");
        // Panics, with the message, when a check fails.
        let outcomes = workspace.check(&input);
        if name.starts_with("seed-") {
            seeds += 1;
            for outcome in &outcomes {
                assert!(!outcome.ends_with(":ok"), "{name}: {outcomes:?}");
            }
        }
    }
    assert!(seeds >= 3, "the seeds of testdata/fuzz-config/ are missing");
}

/// Limits with the limit in the message, and messages in the file's terms.
#[test]
fn limits_and_type_errors_speak_in_the_files_terms() {
    let digits = format!("max_velocity: -1{}", "0".repeat(308));
    let joints = "max_velocity: 180\n        max_acceleration: 900\n      - name: b";
    let cases = [
        (
            "latency-list",
            "baud: 1000000",
            "baud: 1000000\n    latency_us: [5]".to_owned(),
            (7, 17, "buses[0].latency_us"),
            "invalid type: sequence, expected a number of microseconds or `auto`",
        ),
        (
            "latency-long",
            "baud: 1000000",
            "baud: 1000000\n    latency_us: 300000".to_owned(),
            (7, 17, "buses[0].latency_us"),
            "300000 us is not an adapter latency: give 0 to 255000 us",
        ),
        (
            "rate",
            "rate: 100",
            "rate: 5".to_owned(),
            (3, 7, "rate"),
            "5 Hz is outside the control rates servobus runs, 10 to 10000 Hz",
        ),
        (
            "digits",
            joints,
            format!("{digits}\n        max_acceleration: 900\n      - name: b"),
            (13, 23, "buses[0].joints[0].max_velocity"),
            "must be positive, got -1e308",
        ),
    ];
    for (test, from, to, (line, column, field), reason) in cases {
        let (p, e) = robot_error(test, from, &to);
        expect(&e, &p, line, column, field, reason);
    }
    let list = write("list", "robot.yaml", "- name: x\n");
    let text = load_robot(&list, &RobotOptions::default())
        .expect_err("a list is not a robot")
        .to_string();
    let said = format!(
        "{}:1:1: invalid type: sequence, expected a robot file: a mapping with `name:`",
        list.display()
    );
    assert!(text.starts_with(&said), "{text}");
}

/// A motion cannot ask for unbounded work: the loader refuses a billion
/// repetitions and a keyframe at 1e12 s, and the planner a motion that
/// would last longer than a day; each names the limit.
#[test]
fn motions_are_capped_with_the_limit_in_the_message() {
    let (p, e) = motion_error(
        "repeat_cap",
        "robot: robot.yaml\nkeyframes:\n  - pose: {a: 0}\n  - pose: {a: 10}\nrepeat: 1000000000\n",
    );
    let reason = "2 keyframes x 1000000000 repetitions x 2 joints is 4e9 joint segments to plan, \
                  more than the limit of 500000";
    expect(&e, &p, 5, 9, "repeat", reason);
    let (p, e) = motion_error(
        "at_cap",
        "robot: robot.yaml\nkeyframes:\n  - pose: {a: 0}\n  - at: 1e12\n    pose: {a: 10}\n",
    );
    let reason = "1e12 s is longer than the limit of 86400 s (a day) for one motion";
    expect(&e, &p, 4, 9, "keyframes[1].at", reason);
    // A joint of 1e-6 deg/s takes 1e7 s for 10 deg: the plan is refused.
    let slow = ROBOT.replacen("max_velocity: 180", "max_velocity: 0.000001", 1);
    write("slow_cap", "robot.yaml", &slow);
    let p = write(
        "slow_cap",
        "motion.yaml",
        "robot: robot.yaml\nkeyframes:\n  - pose: {a: 0}\n  - pose: {a: 10}\n",
    );
    let (motion, robot) = load_motion(&p, None).expect("the files are valid");
    let e = servobus_config::plan_motion(&motion, &robot).expect_err("too long");
    let reason = "the motion is too long: 10000000 s is longer than the limit of 86400 s";
    expect(&e, &p, 4, 5, "keyframes[1]", reason);
}

#[test]
fn a_duplicate_key_is_placed_at_its_second_line_and_names_the_first() {
    // A line added twice at the end of the file (a step of a walkthrough
    // run twice): the mapping starts at line 1, the keys follow the robot's last line.
    let twice = format!("{ROBOT}calibration: cal.yaml\ncalibration: cal.yaml\n");
    let p = write("duplicate_root", "robot.yaml", &twice);
    let e = load_robot(&p, &RobotOptions::default()).expect_err("a duplicate key");
    let lines = ROBOT.lines().count();
    let said = format!(
        "{}:{}:1: duplicate field `calibration` (first given at line {})",
        p.display(),
        lines + 2,
        lines + 1
    );
    assert_eq!(e.to_string(), said);
    // Inside a list item's mapping: the second `id:` of joint b.
    let (p, e) = robot_error(
        "duplicate_joint",
        "        id: 2\n",
        "        id: 2\n        id: 3\n",
    );
    expect(&e, &p, 17, 9, "buses[0].joints[1]", "duplicate field `id`");
    assert!(e.to_string().contains("(first given at line 16)"), "{e}");
    // A flow mapping keeps serde_yaml's place (the mapping's start).
    let joint_b = ROBOT.split("      - name: b\n").nth(1).expect("joint b");
    let flow = "      - {name: b, id: 2, id: 3, model: sts3215, min: -45, max: 45, \
                max_velocity: 180, max_acceleration: 900}\n";
    let (p, e) = robot_error(
        "duplicate_flow",
        &format!("      - name: b\n{joint_b}"),
        flow,
    );
    expect(&e, &p, 15, 9, "buses[0].joints[1]", "duplicate field `id`");
    assert!(!e.to_string().contains("first given"), "{e}");
}
