//! End to end: start `servobus sim` on a pty and use `scan`, `ping`, `read`,
//! `write` and `set-id` against it as a user would.
//!
//! The simulator runs in wall-clock time here, so the commands are given a
//! generous adapter latency (`--latency-us`): on a loaded machine the
//! simulator's process may be scheduled milliseconds late. Nothing in this
//! test measures time.

mod common;

use std::process::Output;

use common::Sim;

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn ok(sim: &Sim, args: &[&str]) -> String {
    let o = sim.run(args);
    assert!(
        o.status.success(),
        "servobus {args:?} failed: {}",
        stderr(&o)
    );
    stdout(&o)
}

/// The command fails with exit code 1 and a one-line error containing `why`.
fn fails(sim: &Sim, args: &[&str], why: &str) {
    let o = sim.run(args);
    assert_eq!(o.status.code(), Some(1), "servobus {args:?} should fail");
    let err = stderr(&o);
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err:?}");
    assert!(
        err.starts_with("error: ") && err.contains(why),
        "servobus {args:?}: {err:?} should say {why:?}"
    );
}

/// The command is refused as a usage error: exit code 2, one line naming `why`.
fn refused(sim: &Sim, args: &[&str], why: &str) {
    let o = sim.run(args);
    assert_eq!(
        o.status.code(),
        Some(2),
        "servobus {args:?} is a usage error"
    );
    let err = stderr(&o);
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err:?}");
    assert!(
        err.starts_with("error: ") && err.contains(why),
        "{args:?}: {err:?}"
    );
}

fn read_value(sim: &Sim, id: &str, register: &str) -> i64 {
    let out = ok(sim, &["read", "--id", id, register, "--json"]);
    let v: serde_json::Value = serde_json::from_str(out.trim()).expect("read --json");
    v["value"].as_i64().expect("value")
}

#[test]
fn scan_read_write_set_id_against_the_simulator() {
    let dir = common::scratch("bus-tools");
    let sim = Sim::start(&dir);

    // scan: the six servos of the arm, identified.
    let out = ok(&sim, &["scan", "--json"]);
    let scan: serde_json::Value = serde_json::from_str(out.trim()).expect("scan --json");
    let servos = scan["servos"].as_array().expect("servos");
    let ids: Vec<i64> = servos.iter().filter_map(|s| s["id"].as_i64()).collect();
    assert_eq!(ids, [1, 2, 3, 4, 5, 6]);
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
    let table = ok(&sim, &["scan"]);
    assert!(table.contains("POSITION") && table.contains("found 6 servo(s)"));

    // ping and read.
    assert!(ok(&sim, &["ping", "--id", "4"]).contains("servo 4 answered"));
    assert_eq!(read_value(&sim, "3", "model_number"), 777);
    let pos = read_value(&sim, "3", "present_position");
    assert!((0..4096).contains(&pos));
    assert!(ok(&sim, &["read", "--id", "3", "Present_Voltage"]).starts_with("present_voltage = "));

    // write: RAM takes effect; EEPROM says it persists and is verified.
    ok(&sim, &["write", "--id", "3", "acceleration", "20"]);
    assert_eq!(read_value(&sim, "3", "acceleration"), 20);
    let out = ok(&sim, &["write", "--id", "3", "max_temperature", "65"]);
    assert!(out.contains("persist") && out.contains("verified"), "{out}");
    assert_eq!(read_value(&sim, "3", "max_temperature"), 65);
    assert_eq!(read_value(&sim, "3", "lock"), 1);

    // set-id: refuses a taken ID, then moves servo 3 to 9.
    fails(&sim, &["set-id", "--id", "3", "2"], "already taken");
    let out = ok(&sim, &["set-id", "--id", "3", "9"]);
    assert!(out.contains("now ID 9"), "{out}");
    assert!(ok(&sim, &["ping", "--id", "9"]).contains("servo 9 answered"));
    fails(&sim, &["ping", "--id", "3"], "servo 3");
    assert_eq!(read_value(&sim, "9", "id"), 9);

    // One-line errors for what a user gets wrong.
    refused(
        &sim,
        &["read", "--id", "1", "nonsense"],
        "no register called",
    );
    refused(
        &sim,
        &["write", "--id", "1", "present_position", "5"],
        "read-only",
    );
    refused(
        &sim,
        &["write", "--id", "1", "acceleration", "300"],
        "acceleration takes",
    );

    let link = sim.link.clone();
    sim.stop();
    assert!(!link.exists(), "sim removes its link on exit");
    let _ = std::fs::remove_dir_all(&dir);
}
