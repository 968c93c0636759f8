//! `servobus calibrate` on the command line, and `play`/`bench` refusing
//! to move servos that do not match the robot's calibration.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::{arg, exited, repo, says, scratch, servobus, servobus_ok, stdout, write_file, Sim};

const LEROBOT: &str = "crates/robot/tests/data/so101-lerobot.json";
const SO101: &str = "configs/robots/so101.yaml";

/// `servobus calibrate --from-lerobot FROM -o TO` for the SO-101.
fn import_lerobot(from: &Path, to: &Path) {
    servobus_ok(&[
        "calibrate",
        "--robot",
        SO101,
        "--from-lerobot",
        arg(from),
        "-o",
        arg(to),
    ]);
}

/// `servobus calibrate` of the SO-101 on `port`, importing the LeRobot
/// fixture into `to` and storing it in the servos (`--write-servos`), with
/// `more` arguments; it must succeed.
fn import_to_servos(port: &str, to: &Path, more: &[&str]) -> Output {
    let lerobot = repo(LEROBOT);
    let args = import_to_servos_args(port, &lerobot, to);
    servobus_ok(&[&args[..], more].concat())
}

/// The arguments of `servobus calibrate` of the SO-101 on `port`,
/// importing the LeRobot file `lerobot` into `to` and storing it in the
/// servos (`--write-servos`).
fn import_to_servos_args<'a>(port: &'a str, lerobot: &'a Path, to: &'a Path) -> [&'a str; 10] {
    [
        "calibrate",
        "--robot",
        SO101,
        "--port",
        port,
        "--from-lerobot",
        arg(lerobot),
        "--write-servos",
        "-o",
        arg(to),
    ]
}

/// The SO-101 robot file, copied to `dir` with `calibration: FILE` added.
fn robot_naming(dir: &Path, calibration: &str) -> PathBuf {
    let text = std::fs::read_to_string(repo(SO101)).expect("so101");
    write_file(
        dir,
        "so101.yaml",
        &format!("calibration: {calibration}\n{text}"),
    )
}

/// The run was refused, for `why`, before anything moved, and the user is
/// told what to run.
fn assert_refused(out: &Output, why: &str) {
    let (_, err) = exited(out, 1);
    says(
        &err,
        &[why, "nothing was moved", "servobus calibrate --robot"],
    );
}

#[test]
fn a_lerobot_file_goes_through_calibrate_and_comes_back_identical() {
    let dir = scratch("calib-lerobot");
    let cal = dir.join("arm.calibration.yaml");
    let json = dir.join("back.json");
    import_lerobot(&repo(LEROBOT), &cal);
    servobus_ok(&[
        "calibrate",
        "--robot",
        SO101,
        "--to-lerobot",
        arg(&json),
        "--calibration",
        arg(&cal),
    ]);
    let original = std::fs::read_to_string(repo(LEROBOT)).expect("fixture");
    assert_eq!(std::fs::read_to_string(&json).expect("exported"), original);
}

#[test]
fn plan_play_and_bench_refuse_a_missing_calibration_before_moving_anything() {
    let dir = scratch("calib-missing");
    let robot = robot_naming(&dir, "arm.calibration.yaml");
    let sim = Sim::start(&dir);
    let (port, robot) = (sim.port(), arg(&robot));
    let before = sim.read("2", "present_position");
    let wave = "configs/motions/arm-wave.yaml";
    // play refuses the robot as it loads it (an input error: exit 2).
    let out = servobus(&["play", wave, "--port", port, "--robot", robot]);
    let (_, err) = exited(&out, 2);
    says(
        &err,
        &[
            "arm.calibration.yaml does not exist",
            "servobus calibrate --robot",
        ],
    );
    let out = servobus(&[
        "bench",
        "--seconds",
        "0.2",
        "--port",
        port,
        "--robot",
        robot,
    ]);
    // A robot file naming a file that is not there: an input error, as for
    // play (exit 2).
    let (_, err) = exited(&out, 2);
    says(
        &err,
        &[
            "does not exist",
            "nothing was moved",
            "servobus calibrate --robot",
        ],
    );
    // Torque was never switched on, and the joint is where it was.
    assert_eq!(sim.read("2", "torque_enable"), 0);
    assert_eq!(sim.read("2", "present_position"), before);
    // Nor is it planned, or played on the built-in simulator: its limits
    // are the calibration's.
    for args in [
        &["plan", wave, "--robot", robot][..],
        &["play", wave, "--fast", "--robot", robot],
    ] {
        let (_, err) = exited(&servobus(args), 2);
        says(
            &err,
            &[
                "calibration: the calibration file",
                "arm.calibration.yaml does not exist",
            ],
        );
    }
    sim.stop();
}

#[test]
fn play_refuses_servos_that_do_not_match_the_calibration() {
    let dir = scratch("calib-mismatch");
    // LeRobot's calibration of another arm: its servos hold homing offsets
    // that the simulated ones (offset 0) do not.
    let other = dir.join("other.calibration.yaml");
    import_lerobot(&repo(LEROBOT), &other);
    let sim = Sim::start(&dir);
    // `play` on the simulator's port with a calibration file.
    let play_with = |calibration: &Path| {
        let wave = "configs/motions/arm-wave.yaml";
        servobus(&[
            "play",
            wave,
            "--port",
            sim.port(),
            "--calibration",
            arg(calibration),
        ])
    };
    let out = play_with(&other);
    assert_refused(
        &out,
        "holds homing offset 0, the calibration was taken with -1389",
    );

    // Offsets that match, but a range the joint is nowhere near.
    let json = std::fs::read_to_string(repo(LEROBOT)).expect("fixture");
    let mut v: serde_json::Value = serde_json::from_str(&json).expect("json");
    for (_, m) in v.as_object_mut().expect("object").iter_mut() {
        m["homing_offset"] = 0.into();
    }
    v["shoulder_pan"]["range_min"] = 100.into();
    v["shoulder_pan"]["range_max"] = 900.into();
    let moved = dir.join("moved.json");
    std::fs::write(&moved, v.to_string()).expect("write json");
    let far = dir.join("far.calibration.yaml");
    import_lerobot(&moved, &far);
    let out = play_with(&far);
    assert_refused(&out, "far outside its calibrated range");
    assert_eq!(sim.read("1", "torque_enable"), 0);
    sim.stop();
}

/// The Python with LeRobot (SERVOBUS_LEROBOT_PYTHON, as prepared by
/// `scripts/python_clients.sh`). The test that needs it is ignored in the
/// default run; asked for (`--ignored`, as the gate does), it fails without
/// it rather than pass without running.
fn lerobot_python() -> std::ffi::OsString {
    std::env::var_os("SERVOBUS_LEROBOT_PYTHON").unwrap_or_else(|| {
        panic!(
            "no Python with LeRobot: run `eval \"$(bash scripts/python_clients.sh)\"` \
             (it sets SERVOBUS_LEROBOT_PYTHON), then run this test again"
        )
    })
}

/// A LeRobot calibration imported and written to the servos, exported
/// again: LeRobot's own bus accepts it as calibrated, and its DEGREES,
/// RANGE_M100_100 and RANGE_0_100 readings of the servos are what servobus
/// says they are.
#[test]
#[ignore = "needs LeRobot 0.6.1: `eval \"$(bash scripts/python_clients.sh)\"` sets SERVOBUS_LEROBOT_PYTHON, then `cargo test --test cli -- --ignored` (the gate runs it)"]
fn lerobot_accepts_the_exported_calibration_and_reads_the_same_pose() {
    use servobus_robot::calibrate::{lerobot_value, NormMode};
    use servobus_runtime::config::{load_robot, JointMap, RobotOptions};
    let python = lerobot_python();
    let dir = scratch("calib-lerobot-check");
    let sim = Sim::start(&dir);
    let port = sim.port();
    let cal = dir.join("arm.calibration.yaml");
    let json = dir.join("arm.json");
    let out = import_to_servos(port, &cal, &["--to-lerobot", arg(&json)]);
    let text = stdout(&out);
    assert_eq!(
        text.matches("(unlocked, written, verified, locked)")
            .count(),
        6,
        "{text}"
    );
    assert_eq!(
        std::fs::read_to_string(&json).expect("exported"),
        std::fs::read_to_string(repo(LEROBOT)).expect("fixture")
    );
    // Each joint to a pose inside its calibrated range (the simulated
    // servos start wherever the robot file's rest puts them).
    let fixture: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(repo(LEROBOT)).expect("fixture"))
            .expect("json");
    for (i, (_, m)) in fixture.as_object().expect("motors").iter().enumerate() {
        let (lo, hi) = (m["range_min"].as_f64(), m["range_max"].as_f64());
        let (lo, hi) = (lo.expect("min"), hi.expect("max"));
        let goal = (lo + (hi - lo) * (0.2 + 0.12 * i as f64))
            .round()
            .to_string();
        let id = m["id"].to_string();
        for (register, value) in [("torque_enable", "1"), ("goal_position", goal.as_str())] {
            // A loaded host may make a reply late; the write is idempotent.
            let args = ["write", "--port", port, "--id", &id, register, value];
            let out = (0..3)
                .map(|_| servobus(&args))
                .find(|o| o.status.success())
                .unwrap_or_else(|| servobus(&args));
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
    }
    std::thread::sleep(std::time::Duration::from_millis(1500));
    // LeRobot's reads give up on one late reply, which a loaded host can
    // cause: up to three tries, the first clean one counts.
    let lerobot_check = || {
        Command::new(&python)
            .arg(repo("tests/python/lerobot_calibration_check.py"))
            .arg(port)
            .arg(&json)
            .output()
            .expect("python runs")
    };
    let check = (0..2)
        .map(|_| lerobot_check())
        .find(|o| o.status.success())
        .unwrap_or_else(lerobot_check);
    let said = String::from_utf8_lossy(&check.stdout);
    assert!(
        check.status.success() && said.contains("OK calibrated"),
        "{said}{}",
        String::from_utf8_lossy(&check.stderr)
    );
    let robot = load_robot(
        &repo(SO101),
        &RobotOptions::default().calibration(Some(&cal)),
    )
    .expect("calibration applies");
    let lines: Vec<&str> = said.lines().filter(|l| !l.starts_with("OK")).collect();
    assert_eq!(lines.len(), 6, "one line per motor: {said}");
    for line in lines {
        let v: Vec<&str> = line.split_whitespace().collect();
        let joint = robot.joint(v[0]).expect("a joint");
        let jc = joint.calibration.as_ref().expect("calibrated");
        let raw: i32 = v[1].parse().expect("raw");
        let deg = JointMap::new(joint, robot.units)
            .from_ticks(raw)
            .to_degrees();
        for (mode, theirs) in [
            (NormMode::Degrees, v[2]),
            (NormMode::RangeM100To100, v[3]),
            (NormMode::Range0To100, v[4]),
        ] {
            let theirs: f64 = theirs.parse().expect("a number");
            let ours = lerobot_value(jc, deg, mode).expect("known model");
            assert!(
                (ours - theirs).abs() < 1e-6,
                "{line}: {mode:?} servobus {ours}"
            );
        }
    }
    sim.stop();
}

/// A robot with two buses and a port for the first only: the missing port
/// is named, as an input error, before any port is opened.
#[test]
fn calibrate_names_the_bus_that_has_no_port() {
    let port = "/nonexistent/servobus-port";
    let out = servobus(&[
        "calibrate",
        "--robot",
        "hexapod-2bus",
        "--port",
        port,
        "--yes",
    ]);
    let (_, err) = exited(&out, 2);
    says(&err, &["bus `right`", "has no port"]);
}

/// An imported calibration stored with `--write-servos`: one line per
/// servo, in the robot's joint order, and each servo's EEPROM holds the
/// homing offset and limits its line says.
#[test]
fn an_import_written_to_the_servos_says_each_servo_and_they_hold_it() {
    let dir = scratch("calib-import-write");
    let sim = Sim::start(&dir);
    let cal = dir.join("arm.calibration.yaml");
    let out = import_to_servos(sim.port(), &cal, &[]);
    let text = stdout(&out);
    let lines: Vec<&str> = text
        .lines()
        .filter(|l| l.ends_with("(unlocked, written, verified, locked)"))
        .collect();
    let heads: Vec<&str> = lines
        .iter()
        .filter_map(|l| l.split_once(": ").map(|(head, _)| head))
        .collect();
    assert_eq!(
        heads,
        [
            "servo 1 (shoulder_pan)",
            "servo 2 (shoulder_lift)",
            "servo 3 (elbow_flex)",
            "servo 4 (wrist_flex)",
            "servo 5 (wrist_roll)",
            "servo 6 (gripper)"
        ],
        "{text}"
    );
    for (id, line) in (1..=6).zip(&lines) {
        let said = format!(
            "Homing_Offset {}, limits {}..{} ",
            sim.read(&id.to_string(), "offset"),
            sim.read(&id.to_string(), "min_angle_limit"),
            sim.read(&id.to_string(), "max_angle_limit")
        );
        assert!(
            line.contains(&said),
            "servo {id}: `{line}` against `{said}`"
        );
    }
    sim.stop();
}

/// `calibrate --write-servos` (a LeRobot import stored in the servos) cut
/// by SIGINT, SIGTERM or a double SIGINT at swept moments, stdout a pipe:
/// each servo is locked and either fully written or exactly as it was;
/// the servos said to be written are those written; the calibration is
/// saved all the same, and the error names the servos written and not.
#[test]
fn calibrate_write_servos_cut_by_a_signal_finishes_each_servo_it_began_and_says_which() {
    use crate::bus_tools::cut;
    use std::time::Duration;
    let dir = scratch("calib-write-cut");
    let sim = Sim::start_with(&dir, cut::SLOW);
    let port = sim.port().to_owned();
    let ids = [1, 2, 3, 4, 5, 6];
    let before = cut::states(&port, &ids);
    let cal = dir.join("arm.calibration.yaml");
    let lerobot = repo(LEROBOT);
    let args = import_to_servos_args(&port, &lerobot, &cal);
    let whole = cut::run(&args, "", 0, Duration::ZERO, &[]);
    assert_eq!(whole.code, Some(0), "{whole:?}");
    let after = cut::states(&port, &ids);
    for (b, a) in before.iter().zip(&after) {
        assert_ne!(b.eeprom, a.eeprom, "the import changes every servo");
    }
    let put_back = |states: &[cut::State]| {
        let mut bus = cut::bus(&port);
        for (&id, s) in ids.iter().zip(states) {
            // Homing offset (31, 32) and the limits (9 to 12).
            bus.write_eeprom_all(id, &[(9, &s.eeprom[9..13]), (31, &s.eeprom[31..33])])
                .expect("put back");
        }
    };
    let mut stopped_between = 0;
    for k in 0..6 {
        put_back(&before);
        let _ = std::fs::remove_file(&cal);
        let wait = Duration::from_millis(25 * (k as u64 % 3));
        let run = cut::run(
            &args,
            "(unlocked, written, verified, locked)",
            k,
            wait,
            cut::signals(k),
        );
        let now = cut::states(&port, &ids);
        let written = cut::written(&before, &after, &now, &run);
        let said: Vec<usize> = run
            .stdout
            .lines()
            .filter(|l| l.ends_with("(unlocked, written, verified, locked)"))
            .filter_map(|l| {
                l.strip_prefix("servo ")?
                    .split(' ')
                    .next()?
                    .parse::<usize>()
                    .ok()
            })
            .map(|id| id - 1)
            .collect();
        assert_eq!(
            said, written,
            "the servos said are the ones written: {run:?}"
        );
        // Ended by the signal before catching any (at its very start):
        // nothing was written. Otherwise the calibration is saved.
        if run.code.is_none() {
            assert!(written.is_empty(), "{run:?}");
            continue;
        }
        assert!(cal.exists(), "no calibration saved: {run:?}");
        if written.len() < ids.len() {
            assert_eq!(run.code, Some(1), "{run:?}");
            says(
                &run.stderr,
                &["stopped by SIG", "servos written", "not written"],
            );
            stopped_between += 1;
        }
    }
    assert!(stopped_between > 0, "no run was stopped part way");
    sim.stop();
}
