//! End to end: start `servobus sim` on a pty and use `scan`, `ping`, `read`,
//! `write` and `set-id` against it as a user would.
//!
//! The simulator runs in wall-clock time here, so the commands are given a
//! generous adapter latency (`--latency-us`): on a loaded machine the
//! simulator's process may be scheduled milliseconds late. Nothing in this
//! test measures time.

use crate::common;

use common::{error, says, Sim};

/// The command fails with exit code `code` (1: a problem found, 2: a usage
/// error) and a one-line error naming `why`.
fn fails(sim: &Sim, args: &[&str], code: i32, why: &str) {
    says(&error(&sim.run(args), code), &[why]);
}

#[test]
fn scan_read_write_set_id_against_the_simulator() {
    let dir = common::scratch("bus-tools");
    let sim = Sim::start(&dir);

    // scan: the six servos of the arm, identified. A scan asks each absent
    // ID once, so a simulator process descheduled for longer than the
    // deadline on a loaded machine can hide a servo from one pass (a
    // servo on a real bus is never descheduled): up to 3 passes, the first
    // complete one counts, and it must say exactly this.
    let json = |out: String| -> serde_json::Value {
        serde_json::from_str(out.trim()).expect("scan --json")
    };
    let ids_of = |scan: &serde_json::Value| -> Vec<i64> {
        let servos = scan["servos"].as_array().expect("servos");
        servos.iter().filter_map(|s| s["id"].as_i64()).collect()
    };
    let scan = (0..2)
        .map(|_| json(sim.scan(&["--json"])))
        .find(|scan| ids_of(scan).len() == 6)
        .unwrap_or_else(|| json(sim.scan(&["--json"])));
    let servos = scan["servos"].as_array().expect("servos");
    assert_eq!(ids_of(&scan), [1, 2, 3, 4, 5, 6]);
    for s in servos {
        assert_eq!(s["model"], "STS3215");
        assert_eq!(s["model_number"], 777);
        assert!(s["voltage_v"].as_f64().is_some_and(|v| v > 4.0));
        assert!(s["position"]
            .as_i64()
            .is_some_and(|p| (0..4096).contains(&p)));
    }
    assert_eq!(scan["collisions"].as_array().map(Vec::len), Some(0));
    // The table form names the columns.
    let table = (0..2)
        .map(|_| sim.scan(&[]))
        .find(|t| t.contains("found 6 servo(s)"))
        .unwrap_or_else(|| sim.scan(&[]));
    assert!(
        table.contains("POSITION") && table.contains("found 6 servo(s)"),
        "{table}"
    );

    // ping and read.
    assert!(sim.ok(&["ping", "--id", "4"]).contains("servo 4 answered"));
    assert_eq!(sim.read("3", "model_number"), 777);
    let pos = sim.read("3", "present_position");
    assert!((0..4096).contains(&pos));
    assert!(sim
        .ok(&["read", "--id", "3", "Present_Voltage"])
        .starts_with("present_voltage = "));

    // write: RAM takes effect; EEPROM says it persists and is verified.
    sim.ok(&["write", "--id", "3", "acceleration", "20"]);
    assert_eq!(sim.read("3", "acceleration"), 20);
    let out = sim.ok(&["write", "--id", "3", "max_temperature", "65"]);
    assert!(out.contains("persist") && out.contains("verified"), "{out}");
    assert_eq!(sim.read("3", "max_temperature"), 65);
    assert_eq!(sim.read("3", "lock"), 1);

    // set-id: refuses a taken ID, then moves servo 3 to 9.
    fails(&sim, &["set-id", "--id", "3", "2"], 1, "already taken");
    let out = sim.ok(&["set-id", "--id", "3", "9"]);
    assert!(out.contains("now ID 9"), "{out}");
    assert!(sim.ok(&["ping", "--id", "9"]).contains("servo 9 answered"));
    fails(&sim, &["ping", "--id", "3"], 1, "servo 3");
    assert_eq!(sim.read("9", "id"), 9);

    // One-line errors for what a user gets wrong.
    for (args, why) in [
        (&["read", "--id", "1", "nonsense"][..], "no register called"),
        (
            &["read", "--id", "1", "nonsense"][..],
            "goal_position, goal_time, goal_speed",
        ),
        (
            &["write", "--id", "1", "nonsense", "1"][..],
            "servobus registers --series sts",
        ),
        (
            &["write", "--id", "1", "present_position", "5"],
            "read-only",
        ),
        (
            &["write", "--id", "1", "acceleration", "300"],
            "acceleration takes",
        ),
    ] {
        fails(&sim, args, 2, why);
    }

    let link = sim.link.clone();
    sim.stop();
    assert!(!link.exists(), "sim removes its link on exit");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn registers_lists_each_series_table() {
    let sts = common::stdout(&common::servobus_ok(&["registers", "--series", "sts"]));
    // Address, size, access and name, by hand from Feetech's STS table.
    says(
        &sts,
        &[
            "  42    2  RAM       goal_position",
            "  55    1  RAM       lock",
            "   6    1  EEPROM    baud_rate",
            "  56    2  read-only present_position",
        ],
    );
    assert!(!sts.contains("SCS servos"), "{sts}");
    let scs = common::stdout(&common::servobus_ok(&["registers", "--series", "scs"]));
    assert!(scs.contains("  48    1  RAM       lock"), "{scs}");
    let both = common::stdout(&common::servobus_ok(&["registers"]));
    assert!(
        both.contains("STS servos") && both.contains("SCS servos"),
        "{both}"
    );
    let out = common::servobus(&["registers", "--series", "xl"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn the_simulators_examples_are_built_in_and_listed() {
    let list = common::stdout(&common::servobus_ok(&["list"]));
    says(
        &list,
        &[
            "so101-mounting",
            "so101-hand",
            "--mounting NAME",
            "--hand NAME",
        ],
    );
    // By name (no file of that name in the working directory).
    let dir = common::scratch("sim-examples");
    let sim = Sim::start_with(&dir, &["--mounting", "so101-mounting"]);
    // The mounting puts shoulder_pan's zero (its rest) at tick 1300.
    assert_eq!(sim.read("1", "present_position"), 1300);
    sim.stop();
    // The hand loads and the simulator serves with it.
    Sim::start_with(&dir, &["--hand", "so101-hand"]).stop();
    let _ = std::fs::remove_dir_all(&dir);
}
