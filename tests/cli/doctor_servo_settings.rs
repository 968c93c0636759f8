//! `servobus doctor` and what a robot file asks of the servos' EEPROM (a
//! wheel joint's operating mode, a `servo: {p: 16}`), end to end on
//! `servobus sim` on a pseudo-terminal, whose servos keep what was written
//! between runs and start as a new servo does (every one in position mode,
//! P 32): the text, the hint and `--json`. The built-in simulator starts
//! its servos as the robot file asks for the mode.

use crate::common;

use common::{arg, exited, json, says, scratch, servobus, write_file, Sim};

/// A robot with a position joint `arm` (servo 1, `servo: {p: 16}`) and a
/// wheel `drive` (servo 2).
const ROVER: &str = "\
name: rover
units: deg
buses:
  - name: b
    joints:
      - name: arm
        id: 1
        model: sts3215
        min: -90
        max: 90
        max_velocity: 180
        max_acceleration: 900
        servo: {p: 16, torque_limit: 60}
      - name: drive
        id: 2
        model: sts3215
        mode: wheel
        max_velocity: 250
        max_acceleration: 500
";

/// The same bus as the servos come from the box: servo 2 still a position
/// servo (mode 0), as a simulator of this file starts it.
const FRESH: &str = "\
name: rover
units: deg
buses:
  - name: b
    joints:
      - name: arm
        id: 1
        model: sts3215
        min: -90
        max: 90
        max_velocity: 180
        max_acceleration: 900
      - name: drive
        id: 2
        model: sts3215
        min: -90
        max: 90
        max_velocity: 180
        max_acceleration: 900
";

/// `servobus sim` of the servos as they come from the box, on a pty in
/// `dir`, and `rover.yaml` there, the robot file that asks for more.
fn fresh_servos(dir: &std::path::Path) -> (Sim, std::path::PathBuf) {
    let fresh = write_file(dir, "fresh.yaml", FRESH);
    let robot = write_file(dir, "rover.yaml", ROVER);
    (Sim::start_robot(dir, &fresh, 2, &[]), robot)
}

/// The finding of `findings` (a JSON list) about servo `id`'s `register`.
fn about<'a>(findings: &'a serde_json::Value, id: u64, register: &str) -> &'a serde_json::Value {
    findings
        .as_array()
        .and_then(|l| {
            l.iter()
                .find(|f| f["id"].as_u64() == Some(id) && f["register"] == register)
        })
        .unwrap_or_else(|| panic!("nothing about servo {id} {register}: {findings}"))
}

#[test]
fn the_built_in_simulator_starts_a_wheels_servo_in_its_mode() {
    let dir = scratch("doctor-servo-settings-built-in");
    let robot = write_file(&dir, "rover.yaml", ROVER);
    // Only a warning (exit 1): the P coefficient is EEPROM, which a new
    // servo holds at 32.
    let (text, _) = exited(&servobus(&["doctor", "--robot", arg(&robot)]), 1);
    assert!(!text.contains("servo 2 mode"), "{text}");
    says(&text, &["WARNING  servo 1 p_coefficient"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn new_servos_mode_and_p_are_reported_and_fixed_only_with_write_servos() {
    let dir = scratch("doctor-servo-settings");
    let (sim, robot) = fresh_servos(&dir);
    let doctor = ["doctor", "--robot", arg(&robot), "--port", sim.port()];

    let (text, _) = exited(&servobus(&doctor), 2);
    says(
        &text,
        &[
            "ERROR    servo 2 mode: operating mode is 0 (position), joint `drive` is a wheel",
            "fix [--fix --write-servos]: servobus doctor --robot",
            "WARNING  servo 1 p_coefficient: p_coefficient (register 21) is 32, joint `arm`'s \
             `servo: p` asks for 16",
            "1 error(s), 1 warning(s); 2 with --fix --write-servos (EEPROM)",
        ],
    );
    // The torque limit is RAM, which the run writes: no finding.
    assert!(!text.contains("torque_limit"), "{text}");

    // --fix alone: both skipped, nothing applied, so nothing examined again.
    let out = servobus(&[&doctor[..], &["--fix"]].concat());
    let (text, _) = exited(&out, 2);
    for id in [1, 2] {
        says(
            &text,
            &[&format!(
                "skipped  servo {id}: only an EEPROM write fixes this: give --fix --write-servos"
            )],
        );
    }
    assert!(!text.contains("after the fixes"), "{text}");

    let out = servobus(&[&doctor[..], &["--fix", "--write-servos"]].concat());
    let (text, _) = exited(&out, 0);
    says(
        &text,
        &[
            "fixed    servo 2: mode 1 (wheel) stored in EEPROM, the torque turned off first",
            "fixed    servo 1: p_coefficient 16 stored in EEPROM",
            "after the fixes:",
            "0 error(s), 0 warning(s)",
        ],
    );
    sim.stop();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn json_gives_what_the_file_asks_beside_what_the_servo_holds() {
    let dir = scratch("doctor-servo-settings-json");
    let (sim, robot) = fresh_servos(&dir);
    let doctor = ["doctor", "--robot", arg(&robot), "--port", sim.port()];
    let out = servobus(&[&doctor[..], &["--json"]].concat());
    assert_eq!(out.status.code(), Some(2));
    let v = json(&out);
    let findings = &v["buses"][0]["findings"];
    let mode = about(findings, 2, "mode");
    assert_eq!(mode["severity"], "error");
    assert_eq!(mode["measured"], 0);
    assert_eq!(mode["fix_flags"], "--fix --write-servos");
    assert_eq!(
        mode["setting"],
        serde_json::json!({
            "joint": "drive", "setting": "mode", "register": "mode", "address": 33,
            "found": 0, "wanted": 1, "found_as": "position", "wanted_as": "wheel",
        })
    );
    let p = about(findings, 1, "p_coefficient");
    assert_eq!(p["severity"], "warning");
    assert_eq!(p["setting"]["setting"], "p");
    assert_eq!(
        (&p["setting"]["found"], &p["setting"]["wanted"]),
        (&32.into(), &16.into())
    );
    // Other findings keep their shape, with no setting.
    let others: Vec<_> = findings
        .as_array()
        .expect("findings")
        .iter()
        .filter(|f| f["register"] != "mode" && f["register"] != "p_coefficient")
        .collect();
    assert!(!others.is_empty(), "{v}");
    assert!(others.iter().all(|f| f["setting"].is_null()), "{v}");

    let out = servobus(&[&doctor[..], &["--json", "--fix", "--write-servos"]].concat());
    assert_eq!(out.status.code(), Some(0));
    let v = json(&out);
    let bus = &v["buses"][0];
    let fixes = bus["fixes"].as_array().expect("fixes");
    assert_eq!(fixes.len(), 2, "{v}");
    assert!(fixes.iter().all(|f| f["ok"] == true), "{v}");
    let after = bus["after_fix"].as_array().expect("examined again");
    assert!(after.iter().all(|f| f["setting"].is_null()), "{v}");
    sim.stop();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn on_a_pty_the_mode_is_written_only_with_write_servos_and_stays_written() {
    let dir = scratch("doctor-servo-settings-pty");
    let (sim, robot) = fresh_servos(&dir);
    let doctor = ["doctor", "--robot", arg(&robot), "--port", sim.port()];

    let (text, _) = exited(&servobus(&[&doctor[..], &["--fix"]].concat()), 2);
    says(&text, &["skipped  servo 2", "give --fix --write-servos"]);
    assert_eq!(
        sim.read("2", "mode"),
        0,
        "nothing written without --write-servos"
    );
    assert_eq!(sim.read("1", "p_coefficient"), 32);

    let out = servobus(&[&doctor[..], &["--fix", "--write-servos"]].concat());
    let (text, _) = exited(&out, 0);
    says(
        &text,
        &["fixed    servo 2: mode 1 (wheel) stored in EEPROM"],
    );
    assert_eq!(sim.read("2", "mode"), 1);
    assert_eq!(sim.read("2", "torque_enable"), 0);
    assert_eq!(sim.read("1", "p_coefficient"), 16);
    assert_eq!(sim.read("2", "lock"), 1, "locked again");

    // A later run finds them as the robot file asks.
    let (text, _) = exited(&servobus(&doctor), 0);
    assert!(!text.contains("servo 2 mode"), "{text}");
    assert!(!text.contains("p_coefficient"), "{text}");
    sim.stop();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_run_refuses_a_servo_in_the_wrong_mode_and_stores_it_with_write_servos() {
    let dir = scratch("run-write-servos-pty");
    let (sim, robot) = fresh_servos(&dir);
    let stream = ["stream", "--robot", arg(&robot), "--port", sim.port()];

    // Without the flag: refused before anything moves, naming the flag.
    let out = servobus(&stream);
    assert!(!out.status.success(), "{out:?}");
    let text = common::stderr(&out);
    says(
        &text,
        &[
            "joint `drive` (servo 2) is in operating mode 0 (position)",
            "`--write-servos` on the command that runs",
        ],
    );
    assert_eq!(sim.read("2", "mode"), 0, "nothing written without the flag");
    assert_eq!(sim.read("1", "p_coefficient"), 32);

    // With it: each register stored is said, and the run goes on (its
    // input ends at once, so it stops and reports).
    let out = servobus(&[&stream[..], &["--write-servos"]].concat());
    let (_, text) = exited(&out, 0);
    says(
        &text,
        &[
            "bus `b`: joint `drive` (servo 2): stored mode (register 33) position (0) -> wheel (1)",
            "bus `b`: joint `arm` (servo 1): stored p_coefficient (register 21) 32 -> 16",
        ],
    );
    assert_eq!(sim.read("2", "mode"), 1);
    assert_eq!(sim.read("1", "p_coefficient"), 16);
    assert_eq!(sim.read("2", "lock"), 1, "locked again");

    // A servo that holds what the file asks is left alone.
    let out = servobus(&[&stream[..], &["--write-servos"]].concat());
    let (_, text) = exited(&out, 0);
    assert!(!text.contains("stored"), "{text}");
    sim.stop();
    let _ = std::fs::remove_dir_all(&dir);
}
