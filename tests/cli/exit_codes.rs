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
fn a_calibration_file_named_but_missing_exits_2_from_every_command_that_needs_it() {
    let dir = scratch("exit-codes-missing-calibration");
    let so101 = std::fs::read_to_string(common::repo("configs/robots/so101.yaml")).expect("so101");
    let robot = write_file(
        &dir,
        "arm.yaml",
        &format!("calibration: gone.yaml\n{so101}"),
    );
    let robot = arg(&robot);
    let taught = dir.join("taught.yaml");
    let sim = Sim::start(&dir);
    let port = sim.port();
    let commands: [Vec<&str>; 5] = [
        vec!["play", "arm-wave", "--robot", robot, "--port", port],
        vec!["bench", "--robot", robot, "--port", port, "--seconds", "1"],
        vec![
            "teach",
            "--robot",
            robot,
            "--port",
            port,
            "-o",
            arg(&taught),
            "--yes",
        ],
        vec!["doctor", "--robot", robot, "--port", port],
        vec!["play", "arm-wave", "--robot", robot],
    ];
    for args in commands {
        let out = servobus(&args);
        let (stdout, err) = exited(&out, 2);
        let said = format!("{stdout}{err}");
        says(&said, &["gone.yaml"]);
        assert!(
            said.contains("servobus calibrate --robot"),
            "{args:?}: {said}"
        );
    }
    assert!(!taught.exists(), "teach wrote nothing");
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

/// Stdout that cannot be written is an error, never a panic (101): a
/// full one (`> /dev/full`) fails `play` before anything moves, and
/// `plan --json`, with exit 1 and the reason.
#[test]
fn a_full_stdout_exits_1_without_a_panic() {
    let full = || std::fs::OpenOptions::new().write(true).open("/dev/full");
    if full().is_err() {
        eprintln!("skipped: no /dev/full");
        return;
    }
    for args in [
        &["play", "arm-wave", "--fast"][..],
        &["plan", "arm-wave", "--json"][..],
        &["list"][..],
        &["completions", "bash"][..],
    ] {
        let out = Command::new(BIN)
            .args(args)
            .stdout(full().expect("/dev/full"))
            .output()
            .expect("servobus runs");
        let err = error(&out, 1);
        says(&err, &["cannot write to stdout", "the disk is full"]);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

/// The rows of a `play --log` CSV as (time s, joint, commanded, measured),
/// each row checked whole: as many fields as the header, numbers where
/// numbers belong.
fn log_rows(log: &std::path::Path) -> Vec<(f64, String, f64, Option<f64>)> {
    let text = std::fs::read_to_string(log).expect("the log");
    assert!(text.ends_with('\n'), "the log ends with a whole row");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let (t, j, c, m) = (
        col("time_s"),
        col("joint"),
        col("commanded_deg"),
        col("measured_deg"),
    );
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), header.len(), "a whole row: {l}");
            let num = |i: usize| f[i].parse::<f64>().expect("a number");
            (num(t), f[j].to_owned(), num(c), f[m].parse().ok())
        })
        .collect()
}

/// Each joint's `max_acceleration` in the robot file `robot` (read from
/// the YAML here, not by servobus).
fn max_accelerations(robot: &str) -> Vec<(String, f64)> {
    let text = std::fs::read_to_string(common::repo(robot)).expect("the robot file");
    let robot: serde_yaml::Value = serde_yaml::from_str(&text).expect("YAML");
    let buses = robot["buses"].as_sequence().expect("buses");
    let joints = buses
        .iter()
        .flat_map(|b| b["joints"].as_sequence().expect("joints"));
    joints
        .map(|j| {
            let name = j["name"].as_str().expect("a name").to_owned();
            (name, j["max_acceleration"].as_f64().expect("a limit"))
        })
        .collect()
}

/// `play --port P --log L | head -4`: `head` ends once it has the plan's
/// three lines and the first progress line (a second into the run), so
/// the next progress line meets a closed pipe. That is Ctrl-C's first
/// press: the joints stop within their limits and hold with the torque on,
/// the log is written whole, the report goes to stderr, and play exits 1.
#[test]
fn a_closed_stdout_stops_play_jerk_limited_keeps_the_log_and_exits_1() {
    const SO101: &str = "configs/robots/so101.yaml";
    let dir = scratch("exit-codes-closed-stdout");
    let truth = dir.join("truth.csv");
    let sim = Sim::start_with(&dir, &["--truth", arg(&truth)]);
    let log = dir.join("log.csv");
    let mut play = Command::new(BIN)
        .args(["play", "arm-wave", "--robot", SO101, "--port", sim.port()])
        .arg("--log")
        .arg(&log)
        .current_dir(common::repo(""))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("play starts");
    let pipe = play.stdout.take().expect("play's stdout");
    let head = Command::new("head")
        .arg("-4")
        .stdin(Stdio::from(pipe))
        .stdout(Stdio::piped())
        .output()
        .expect("head runs");
    // Bounded: the motion lasts 6 s at most, the stop less.
    let out = play.wait_with_output().expect("play ends");
    let shown = String::from_utf8_lossy(&head.stdout).into_owned();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(
        out.status.code(),
        Some(1),
        "head had:\n{shown}\nstderr:\n{err}"
    );
    assert_eq!(shown.lines().count(), 4, "{shown}");
    assert!(
        shown.lines().nth(3).is_some_and(|l| l.contains(" s  ")),
        "{shown}"
    );
    says(
        &err,
        &[
            "stdout was closed: stopping (jerk-limited), then holding",
            "stopped: ",
            "tracking error",
            "log: ",
            "error: stdout was closed",
        ],
    );
    assert!(!err.contains("panicked"), "{err}");

    // The log is whole, with no temporary left, and ends early: stopped.
    let rows = log_rows(&log);
    let left: Vec<_> = std::fs::read_dir(&dir)
        .expect("the directory lists")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".log.csv"))
        .collect();
    assert!(left.is_empty(), "temporaries left: {left:?}");
    let planned = common::servobus_json(&["plan", "arm-wave", "--robot", SO101, "--json"]);
    let path_s = common::num(&planned, "duration_s");
    let end = rows.last().expect("rows").0;
    assert!(
        end < path_s,
        "stopped before the path's end {path_s} s: {end} s"
    );

    // Within the limits: the goals' acceleration (second differences over
    // 50 ms, where the log's rounding adds under 0.1 deg/s^2) never
    // exceeds the joint's limit, so nothing stopped dead; and the joints
    // end at rest, where the simulator's truth finds them.
    for (joint, acc_limit) in max_accelerations(SO101) {
        let goals: Vec<(f64, f64, Option<f64>)> = rows
            .iter()
            .filter(|r| r.1 == joint)
            .map(|r| (r.0, r.2, r.3))
            .collect();
        let spaced: Vec<(f64, f64)> = goals.iter().step_by(10).map(|g| (g.0, g.1)).collect();
        for w in spaced.windows(3) {
            let v1 = (w[1].1 - w[0].1) / (w[1].0 - w[0].0);
            let v2 = (w[2].1 - w[1].1) / (w[2].0 - w[1].0);
            let acc = (v2 - v1) / ((w[2].0 - w[0].0) / 2.0);
            assert!(
                acc.abs() <= acc_limit * 1.02 + 0.1,
                "{joint}: {acc} deg/s^2 at {} s, beyond {acc_limit}",
                w[1].0
            );
        }
        let last = &goals[goals.len() - 2..];
        let v = (last[1].1 - last[0].1) / (last[1].0 - last[0].0);
        assert!(v.abs() < 0.5, "{joint} ends at rest: {v} deg/s");
    }
    // Held with the torque on, the servos stay where the stop left them.
    for id in 1..=6 {
        assert_eq!(sim.read(&id.to_string(), "torque_enable"), 1, "servo {id}");
    }
    sim.stop();
    let (header, truth_rows) = common::read_truth(&truth);
    let at_end = truth_rows.last().expect("truth rows");
    for (joint, &angle) in header.iter().zip(at_end).skip(1) {
        let logged = rows
            .iter()
            .rev()
            .find(|r| &r.1 == joint)
            .and_then(|r| r.3)
            .expect("a last reading");
        assert!(
            (angle - logged).abs() < 1.0,
            "{joint}: the truth {angle} deg is where the log left it ({logged} deg)"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
