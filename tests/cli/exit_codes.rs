//! Exit codes on the rule "0 ok, 1 problem found, 2 usage or input error",
//! and ports said in the user's terms: every input error of the issue
//! exits 2 with one line; a port another servobus holds is reported busy
//! with its holder's name and pid; a regular file or a directory given as
//! a port is no serial port; `monitor --json` exits 1 when it saw a servo
//! missing or reporting a flag, 0 when every servo was fine.

use crate::common;

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

use common::{arg, error, exited, says, scratch, servobus, write_file, Sim, BIN};

#[test]
fn each_input_error_exits_2_with_one_line() {
    let dir = scratch("exit-codes-input");
    let bad_json = write_file(&dir, "bad.json", "{not json");
    let existing = write_file(&dir, "occupied", "a file, not a link\n");
    let bad_csv = write_file(&dir, "bad.csv", "a,b\n1,2\n");
    let taught = dir.join("taught.yaml");
    let missing = dir.join("none.json");
    let robot = "configs/robots/so101.yaml";
    let sim = Sim::start(&dir);
    let from_lerobot = |file| vec!["calibrate", "--robot", robot, "--from-lerobot", arg(file)];
    let cases: Vec<(Vec<&str>, &[&str])> = vec![
        (vec!["calibrate", "--robot", robot], &["give --port"]),
        (
            vec![
                "calibrate",
                "--robot",
                robot,
                "--from-lerobot",
                arg(&bad_json),
                "--write-servos",
            ],
            &["--write-servos needs", "--port"],
        ),
        (
            from_lerobot(&missing),
            &["cannot read", "none.json", "no such file"],
        ),
        (
            from_lerobot(&bad_json),
            &["bad.json", "not a LeRobot calibration file"],
        ),
        (
            vec!["sim", "--robot", robot, "--faults", "drop=x"],
            &["--faults drop=x", "probability"],
        ),
        (
            vec!["sim", "--robot", robot, "--link", arg(&existing)],
            &["occupied", "not a symbolic link"],
        ),
        (
            vec!["play", arg(&bad_csv), "--robot", robot, "--fast"],
            &["bad.csv", "time_s"],
        ),
        (
            vec![
                "teach",
                "--robot",
                robot,
                "--port",
                sim.port(),
                "--hold",
                "nosuch",
                "-o",
                arg(&taught),
            ],
            &["no joint `nosuch` to hold", "joints: shoulder_pan"],
        ),
        (
            vec!["teach", "--robot", robot, "-o", arg(&taught)],
            &["bus `arm` has no port", "give --port"],
        ),
        (
            vec![
                "play",
                "arm-wave",
                "--robot",
                robot,
                "--fast",
                "--log",
                arg(&dir),
            ],
            &["--log", "is a directory", "nothing was moved"],
        ),
        (
            vec!["monitor", "--robot", robot, "--bus", "nosuch", "--json"],
            &["--bus nosuch", "no such bus", "buses: arm"],
        ),
    ];
    for (args, words) in cases {
        let out = servobus(&args);
        let err = error(&out, 2);
        says(&err, words);
        assert!(!err.contains("os error"), "{args:?}: {err}");
    }
    // A baud rate of 0 is refused by the command line (it used to hang).
    let out = servobus(&["scan", "--port", sim.port(), "--baud", "0"]);
    let (_, err) = exited(&out, 2);
    says(&err, &["--baud", "0"]);
    assert!(
        std::fs::read(&taught).map_or(true, |t| t.is_empty()),
        "teach wrote nothing"
    );
    // Nothing moved: the torque is still off on every servo.
    for id in 1..=6 {
        assert_eq!(sim.read(&id.to_string(), "torque_enable"), 0, "servo {id}");
    }
    sim.stop();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_file_or_a_directory_is_not_a_serial_port() {
    let dir = scratch("exit-codes-not-serial");
    let file = write_file(&dir, "port", "not a port\n");
    for (port, what) in [
        (arg(&file), "(a regular file)"),
        (arg(&dir), "(a directory)"),
    ] {
        let out = servobus(&["ping", "--port", port, "--id", "1"]);
        let err = error(&out, 2);
        says(
            &err,
            &[&format!("cannot open {port}: not a serial port"), what],
        );
        assert!(!err.contains("typewriter"), "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_port_another_servobus_holds_is_busy_and_names_it() {
    let dir = scratch("exit-codes-busy");
    let sim = Sim::start(&dir);
    // A monitor that holds the port for as long as the test needs it.
    let mut holder = Command::new(BIN)
        .args(["monitor", "--port", sim.port(), "--json", "--rate", "2"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("start the holder");
    let mut first = String::new();
    let stdout = holder.stdout.take().expect("stdout");
    let mut reader = BufReader::new(stdout);
    let read = reader.read_line(&mut first);
    if !matches!(read, Ok(n) if n > 0) {
        let _ = holder.kill();
        panic!("the holder printed no frame: {read:?}");
    }
    let out = sim.run(&["ping", "--id", "1"]);
    let pid = holder.id();
    let _ = holder.kill();
    let _ = holder.wait();
    let err = error(&out, 2);
    says(
        &err,
        &[
            &format!("cannot open {}: the port is busy", sim.port()),
            &format!("servobus (pid {pid}) has it open"),
            "close it and retry",
        ],
    );
    // Free again once the holder has gone.
    let out = sim.run(&["ping", "--id", "1"]);
    exited(&out, 0);
    // A servo that does not answer: a problem found, said once.
    let out = sim.run(&["read", "--id", "42", "present_position"]);
    let err = error(&out, 1);
    assert_eq!(err.matches("servo 42").count(), 1, "{err}");
    says(&err, &["no reply"]);
    sim.stop();
    let _ = std::fs::remove_dir_all(&dir);
}

/// `monitor --json --count 2` of the SO-101 arm on a simulator with
/// `faults`: its exit code and its last frame's servo `id`.
fn monitor_json(faults: &str, id: u64) -> (i32, serde_json::Value) {
    let dir = scratch(&format!("exit-codes-monitor-{id}"));
    let sim = Sim::start_with(&dir, &["--faults", faults]);
    let out = Command::new(BIN)
        .args(["monitor", "--robot", "configs/robots/so101.yaml"])
        .args(["--port", sim.port(), "--json", "--count", "2"])
        .current_dir(common::repo(""))
        .output()
        .expect("run servobus");
    sim.stop();
    let _ = std::fs::remove_dir_all(&dir);
    let text = common::stdout(&out);
    let last = text.lines().last().expect("a frame");
    let frame: serde_json::Value = serde_json::from_str(last).expect("JSON");
    let servos = frame["servos"].as_array().expect("servos");
    let row = servos.iter().find(|s| s["id"] == id).expect("the servo");
    (out.status.code().unwrap_or(-1), row.clone())
}

#[test]
fn monitor_json_exits_1_after_seeing_a_missing_or_flagged_servo() {
    let (code, row) = monitor_json("vanish=3", 3);
    assert_eq!(row["present"], false, "{row}");
    assert_eq!(code, 1, "a missing servo is a problem found");

    let (code, row) = monitor_json("overheat=4", 4);
    assert_eq!(row["flags"], serde_json::json!(["overheat"]), "{row}");
    assert_eq!(code, 1, "an overheated servo is a problem found");

    // Every servo fine. On a loaded machine the last read may have come
    // late for one servo (`present` false for that read): one late reply
    // is counted, and is not a missing servo.
    let (code, row) = monitor_json("seed=1", 2);
    assert!(row["replies"].as_u64().is_some_and(|n| n >= 1), "{row}");
    assert!(
        row["missed_in_row"].as_u64().is_some_and(|n| n <= 1),
        "{row}"
    );
    assert_eq!(code, 0, "every servo fine: {row}");
}
