//! `servobus doctor` end to end: the built-in simulator, and `servobus sim
//! --faults` on a pseudo-terminal in wall-clock time (exit status, JSON,
//! `--fix`, every printed fix command run as printed).

use crate::common;

use common::{arg, exited, json, repo, says, scratch, servobus, stderr, stdout, write_file, Sim};

fn doctor_json(args: &[&str]) -> (i32, serde_json::Value) {
    let out = servobus(args);
    (out.status.code().expect("exit code"), json(&out))
}

fn finding<'a>(
    list: &'a serde_json::Value,
    id: u64,
    register: &str,
) -> Option<&'a serde_json::Value> {
    list.as_array()?
        .iter()
        .find(|f| f["id"].as_u64() == Some(id) && f["register"] == register)
}

/// The SO-101's robot file, naming the calibration `calibration`, written
/// to `name` in `dir`.
fn so101_naming(dir: &std::path::Path, name: &str, calibration: &str) -> std::path::PathBuf {
    let so101 = std::fs::read_to_string(repo("configs/robots/so101.yaml")).expect("so101");
    write_file(dir, name, &format!("calibration: {calibration}\n{so101}"))
}

#[test]
fn the_built_in_simulator_has_only_the_gripper_warnings() {
    let out = servobus(&["doctor", "--robot", "configs/robots/so101.yaml"]);
    let (text, _) = exited(&out, 1);
    says(
        &text,
        &[
            "2. configure: the servos' settings\nWARNING  servo 6 max_torque",
            "3. calibrate: the calibration and its homing offsets\nINFO",
            "0 error(s), 3 warning(s); 3 can be fixed with --fix",
        ],
    );
    // No port to run a command on: none is given as runnable.
    let v = json(&servobus(&["doctor", "--robot", "so101", "--json"]));
    let findings = v["buses"][0]["findings"].as_array().expect("findings");
    assert!(!findings.is_empty(), "{v}");
    assert!(findings.iter().all(|f| f["command"].is_null()), "{v}");
    assert!(
        findings.iter().any(|f| f["fix"]
            .as_str()
            .is_some_and(|fix| fix.contains("--port <PORT>"))),
        "{v}"
    );
}

#[test]
fn doctor_finds_faults_on_a_pty_and_fix_brings_a_servo_back_to_the_bus_rate() {
    let dir = scratch("doctor-cli");
    let sim = Sim::start_with(&dir, &["--faults", "baud=4:115200,overheat=3"]);
    let robot = repo("configs/robots/so101.yaml");
    let robot = arg(&robot);
    let (code, v) = doctor_json(&["doctor", "--robot", robot, "--port", sim.port(), "--json"]);
    assert_eq!(code, 2, "{v}");
    let findings = &v["buses"][0]["findings"];
    let baud = finding(findings, 4, "baud_rate").unwrap_or_else(|| panic!("{v}"));
    assert_eq!(baud["severity"], "error");
    assert_eq!(baud["fixable"], true);
    assert_eq!(
        baud["fix"],
        format!(
            "servobus write --port {} --baud 115200 --id 4 baud_rate 0",
            sim.port()
        )
    );
    let hot = finding(findings, 3, "present_temperature").unwrap_or_else(|| panic!("{v}"));
    assert_eq!(hot["severity"], "error");

    let (code, v) = doctor_json(&[
        "doctor",
        "--robot",
        robot,
        "--port",
        sim.port(),
        "--json",
        "--fix",
    ]);
    let fixes = v["buses"][0]["fixes"].as_array().expect("fixes").clone();
    assert!(fixes.iter().all(|f| f["ok"] == true), "{v}");
    assert!(fixes.iter().any(|f| f["id"] == 4), "{v}");
    let after = &v["buses"][0]["after_fix"];
    assert!(finding(after, 4, "baud_rate").is_none(), "{v}");
    // Servo 3 is still hot: --fix does not pretend to cool it.
    assert!(finding(after, 3, "present_temperature").is_some(), "{v}");
    assert_eq!(code, 2);
    let read = servobus(&["read", "--port", sim.port(), "--id", "4", "baud_rate"]);
    assert_eq!(
        String::from_utf8_lossy(&read.stdout).trim(),
        "baud_rate = 0 (1000000 baud)"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_calibration_the_robot_file_names_but_lacks_is_an_error() {
    let dir = scratch("doctor-calibration");
    let robot = so101_naming(&dir, "arm.yaml", "missing.yaml");
    let robot = arg(&robot);
    let (code, v) = doctor_json(&["doctor", "--robot", robot, "--json"]);
    assert_eq!(code, 2, "{v}");
    let findings = v["buses"][0]["findings"].as_array().expect("findings");
    let f = findings
        .iter()
        .find(|f| {
            f["problem"]
                .as_str()
                .is_some_and(|p| p.contains("missing.yaml"))
        })
        .unwrap_or_else(|| panic!("{v}"));
    assert_eq!(f["severity"], "error");
    let fix = f["fix"].as_str().expect("fix");
    assert!(
        fix.starts_with(&format!(
            "servobus calibrate --robot {robot} --port <PORT> -o "
        )),
        "{fix}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A calibration of the SO-101 assembled as the built-in mounting
/// `so101-mounting` says (each joint's pose tick is its zero tick, its
/// direction the mounting's, its range its limits in ticks, unwrapped):
/// shoulder_lift, wrist_flex and the gripper cross the seam, so their
/// servos play with a homing offset set for the session.
const MOUNTED_CALIBRATION: &str = "\
robot: so101
taken: 2026-11-25T12:00:00Z
joints:
  - {name: shoulder_pan, id: 1, model: STS3215, firmware: '3.10', homing_offset: 0, pose_deg: 0, pose_tick: 1300, direction: 1, range: [48, 2552]}
  - {name: shoulder_lift, id: 2, model: STS3215, firmware: '3.10', homing_offset: 0, pose_deg: 0, pose_tick: 3900, direction: 1, range: [2762, 5038]}
  - {name: elbow_flex, id: 3, model: STS3215, firmware: '3.10', homing_offset: 0, pose_deg: 0, pose_tick: 2500, direction: -1, range: [1396, 3604]}
  - {name: wrist_flex, id: 4, model: STS3215, firmware: '3.10', homing_offset: 0, pose_deg: 0, pose_tick: 4796, direction: -1, range: [3715, 5877]}
  - {name: wrist_roll, id: 5, model: STS3215, firmware: '3.10', homing_offset: 0, pose_deg: 0, pose_tick: 2048, direction: 1, range: [228, 3868]}
  - {name: gripper, id: 6, model: STS3215, firmware: '3.10', homing_offset: 0, pose_deg: 0, pose_tick: 3100, direction: 1, range: [3100, 4238]}
";

#[test]
fn every_fix_command_doctor_prints_runs_as_printed_and_leaves_nothing_wrong() {
    let dir = scratch("doctor-commands");
    let robot = so101_naming(&dir, "robot.yaml", "arm.calibration.yaml");
    write_file(&dir, "arm.calibration.yaml", MOUNTED_CALIBRATION);
    let robot = arg(&robot);
    // A badly set-up arm: servo 4 at another baud rate, servo 2 at the
    // factory return delay, servo 3's lock left open, the gripper's
    // factory protection, and no session offsets yet.
    let sim = Sim::start_with(
        &dir,
        &["--mounting", "so101-mounting", "--faults", "baud=4:115200"],
    );
    sim.ok(&["write", "--id", "2", "return_delay", "250"]);
    sim.ok(&["write", "--id", "3", "lock", "0"]);
    let doctor = ["doctor", "--robot", robot, "--port", sim.port()];

    let (code, v) = doctor_json(&[&doctor[..], &["--json"]].concat());
    assert_eq!(code, 2, "{v}");
    let findings = v["buses"][0]["findings"]
        .as_array()
        .expect("findings")
        .clone();
    let mut commands: Vec<String> = Vec::new();
    for f in &findings {
        if let Some(c) = f["command"].as_str() {
            assert!(f["fix"].as_str().is_some_and(|fix| fix.contains(c)), "{f}");
            if !commands.iter().any(|k| k == c) {
                commands.push(c.to_owned());
            }
        }
    }
    let port = sim.port();
    let want = [
        format!("servobus write --port {port} --baud 115200 --id 4 baud_rate 0"),
        format!("servobus write --port {port} --id 2 return_delay 0"),
        format!("servobus write --port {port} --id 3 lock 1"),
        format!("servobus write --port {port} --id 6 max_torque 500"),
        format!("servobus doctor --robot {robot} --port {port} --fix"),
    ];
    for w in &want {
        assert!(commands.contains(w), "{w} not among {commands:#?}");
    }
    // Servos 2 and 6 (servo 4 is read once it is at the bus's rate).
    let offsets: Vec<_> = findings
        .iter()
        .filter(|f| f["register"] == "offset")
        .collect();
    let ids: Vec<u64> = offsets.iter().filter_map(|f| f["id"].as_u64()).collect();
    assert_eq!(ids, [2, 6], "{v}");
    assert!(offsets.iter().all(|f| f["severity"] == "info"), "{v}");
    // The text shows the same commands.
    let text = stdout(&servobus(&doctor));
    for c in &commands {
        assert!(text.contains(c.as_str()), "{c} not in:\n{text}");
    }

    // Each command, exactly as printed, in the order printed.
    for c in &commands {
        let words: Vec<&str> = c.split_whitespace().collect();
        assert_eq!(words[0], "servobus", "{c}");
        let out = servobus(&words[1..]);
        assert_eq!(out.status.code(), Some(0), "`{c}` failed: {}", stderr(&out));
    }

    let (code, v) = doctor_json(&[&doctor[..], &["--json"]].concat());
    let left = v["buses"][0]["findings"].as_array().expect("findings");
    assert!(left.iter().all(|f| f["severity"] == "info"), "{v}");
    assert!(!left.iter().any(|f| f["register"] == "offset"), "{v}");
    assert_eq!(code, 0, "{v}");
    drop(sim);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_builtin_robot_with_a_swapped_id_is_told_the_set_id_sequence() {
    let dir = scratch("doctor-swapped");
    let sim = Sim::start_with(&dir, &["--faults", "duplicate=6:5"]);
    let port = sim.port();
    let out = servobus(&["doctor", "--robot", "so101", "--port", port]);
    let (text, _) = exited(&out, 2);
    says(
        &text,
        &[
            "two servos answer as ID 5 and servo 6 (joint `gripper`) is silent: servo 6 probably has ID 5",
            &format!("run `servobus set-id --port {port} --id 5 6`"),
            &format!("servobus calibrate --robot so101 --port {port} -o my-arm.calibration.yaml"),
        ],
    );
    assert!(!text.contains("<built-in>"), "{text}");
    assert!(
        !text.contains("servo 6 (joint `gripper`) does not answer"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn doctor_exits_2_when_its_port_dies_mid_check() {
    let dir = scratch("doctor-dies");
    let sim = Sim::start(&dir);
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_servobus"))
        .args(["doctor", "--robot", "so101", "--port", sim.port()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("start doctor");
    // Doctor asks 254 IDs, about a second on a pty: the simulator stops
    // while it does (or, on a slow machine, before it opens the port).
    std::thread::sleep(std::time::Duration::from_millis(300));
    sim.stop();
    let out = child.wait_with_output().expect("doctor ends");
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.starts_with("error: "), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn doctors_help_states_its_own_exit_status() {
    let help = stdout(&servobus(&["doctor", "--help"]));
    says(
        &help,
        &[
            "Exit status (doctor's own):",
            "1  warnings only",
            "doctor could not finish",
            "--write-servos",
        ],
    );
    assert!(
        !help.contains("1  a problem was found"),
        "the general rule is not repeated under doctor's own:\n{help}"
    );
}

/// A servo left unlocked and half-written (a write cut by power loss or
/// SIGKILL: the lock open, a new min_angle_limit): play refuses it and
/// names the doctor command, doctor finds it, and --fix mends it.
#[test]
fn a_servo_left_unlocked_and_half_written_is_refused_found_and_mended() {
    use crate::bus_tools::cut;
    let dir = common::scratch("doctor-half-written");
    let sim = Sim::start(&dir);
    let port = sim.port().to_owned();
    {
        let mut bus = cut::bus(&port);
        bus.write(3, 55, &[0]).expect("lock opened");
        // With the lock open a plain write persists: half of a limits pair.
        bus.write(3, 9, &3000u16.to_le_bytes())
            .expect("min_angle_limit");
    }
    let play = common::servobus(&["play", "arm-wave", "--robot", "so101", "--port", &port]);
    let (_, err) = common::exited(&play, 1);
    says(
        &err,
        &[
            "servo 3 has its EEPROM lock open",
            "half-written",
            "nothing was moved",
            &format!("servobus doctor --robot so101 --port {port} --fix"),
        ],
    );
    let doctor = ["doctor", "--robot", "so101", "--port", port.as_str()];
    let found = common::servobus(&doctor);
    let (text, _) = common::exited(&found, 2);
    says(
        &text,
        &[
            "servo 3 lock",
            "EEPROM lock left open",
            "servo 3 min_angle_limit",
        ],
    );
    let fixed = common::servobus(&[&doctor[..], &["--fix"]].concat());
    let text = stdout(&fixed);
    says(&text, &["fixed    servo 3", "lock 1", "min_angle_limit"]);
    let s = cut::state(&port, 3).expect("servo 3");
    assert_eq!(s.lock, 1, "{text}");
    assert!(
        u16::from_le_bytes([s.eeprom[9], s.eeprom[10]]) < 3000,
        "{text}"
    );
    // Found no more.
    let again = stdout(&common::servobus(&doctor));
    assert!(!again.contains("EEPROM lock left open"), "{again}");
    assert!(!again.contains("servo 3 min_angle_limit"), "{again}");
    sim.stop();
}

/// `doctor --fix` cut by SIGINT, SIGTERM or a double SIGINT at swept
/// moments, stdout a pipe: every servo locked, each fix whole or not begun,
/// and the output says which fixes were applied.
#[test]
fn doctor_fix_cut_by_a_signal_applies_each_fix_whole_and_says_which() {
    use crate::bus_tools::cut;
    use std::time::{Duration, Instant};
    let dir = common::scratch("doctor-fix-cut");
    let sim = Sim::start_with(&dir, cut::SLOW);
    let port = sim.port().to_owned();
    let ids = [1, 2, 3];
    let set_delays = |value: u8| {
        let mut bus = cut::bus(&port);
        for id in ids {
            bus.write_eeprom(id, 7, &[value]).expect("return delay");
        }
    };
    set_delays(250);
    let before = cut::states(&port, &ids);
    let args = [
        "doctor",
        "--robot",
        "so101",
        "--port",
        port.as_str(),
        "--fix",
    ];
    let started = Instant::now();
    let whole = cut::run(&args, "", 0, Duration::ZERO, &[]);
    let took = started.elapsed();
    assert!(whole.code.is_some(), "{whole:?}");
    let after = cut::states(&port, &ids);
    for (b, a) in before.iter().zip(&after) {
        assert_ne!(b.eeprom, a.eeprom, "{whole:?}");
    }
    let mut stopped = 0;
    for k in 0..4 {
        set_delays(250);
        let wait = took.mul_f64((k as f64 + 2.0) / 7.0);
        let run = cut::run(&args, "", 0, wait, cut::signals(k));
        let now = cut::states(&port, &ids);
        let written = cut::written(&before, &after, &now, &run);
        for s in cut::states(&port, &[1, 2, 3, 4, 5, 6]) {
            assert_eq!(s.lock, 1, "{run:?}");
        }
        if run.code.is_none() {
            assert!(written.is_empty(), "{run:?}");
            continue;
        }
        let said: Vec<usize> = (0..ids.len())
            .filter(|&i| {
                run.stdout.lines().any(|l| {
                    l.starts_with(&format!("fixed    servo {}: ", ids[i]))
                        && l.contains("return_delay")
                })
            })
            .collect();
        assert_eq!(said, written, "{run:?}");
        if run.stderr.contains("stopped by SIG") {
            assert_eq!(run.code, Some(2), "{run:?}");
            stopped += 1;
        }
    }
    assert!(stopped > 0, "no run was stopped");
    sim.stop();
}

#[test]
fn an_offset_only_an_eeprom_write_fixes_is_marked_so_and_fix_alone_says_it_skipped_it() {
    let dir = scratch("doctor-rewritten-offset");
    let robot = so101_naming(&dir, "robot.yaml", "arm.calibration.yaml");
    write_file(&dir, "arm.calibration.yaml", MOUNTED_CALIBRATION);
    let robot = arg(&robot);
    let sim = Sim::start_with(&dir, &["--mounting", "so101-mounting"]);
    // Another tool re-homed servo 2: neither the calibration's offset nor
    // the one it plays with.
    sim.ok(&["write", "--id", "2", "offset", "500"]);
    let doctor = ["doctor", "--robot", robot, "--port", sim.port()];
    let out = servobus(&doctor);
    let (text, _) = exited(&out, 2);
    let store = format!("servobus write --port {} --id 2 offset", sim.port());
    let marked = text
        .lines()
        .skip_while(|l| !l.contains("servo 2 offset"))
        .nth(1)
        .unwrap_or_default();
    assert!(
        marked.starts_with("         fix [--fix --write-servos]: ") && marked.contains(&store),
        "{text}"
    );
    assert!(
        text.contains("1 with --fix --write-servos (EEPROM)"),
        "{text}"
    );

    let out = servobus(&[&doctor[..], &["--fix"]].concat());
    let (text, _) = exited(&out, 2);
    assert!(
        text.contains(
            "skipped  servo 2: only an EEPROM write fixes this: give --fix --write-servos"
        ),
        "{text}"
    );

    let out = servobus(&[&doctor[..], &["--fix", "--write-servos"]].concat());
    let (text, _) = exited(&out, 0);
    assert!(text.contains("stored in EEPROM"), "{text}");
    assert!(!text.contains("skipped"), "{text}");
    drop(sim);
    let _ = std::fs::remove_dir_all(&dir);
}
