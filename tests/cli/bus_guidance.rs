//! End to end on `servobus sim`: the bus commands guide the user. A register
//! value reads in its unit, a goal written while the torque is off warns,
//! a scan at the wrong baud rate suggests `--all-bauds`, and a port another
//! program holds says so.

use crate::common;

use std::process::Command;

use common::{is_root, repo, servobus_unprivileged, stderr, stdout, Sim};

#[test]
fn bus_commands_say_what_to_do() {
    let dir = common::scratch("bus-guidance");
    let sim = Sim::start(&dir);

    // The voltage register counts 0.1 V: shown in volts, with the raw value.
    let out = sim.run(&["read", "--id", "1", "present_voltage"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let line = stdout(&out);
    let raw: i64 = line
        .split("(raw ")
        .nth(1)
        .and_then(|r| r.trim().trim_end_matches(')').parse().ok())
        .unwrap_or_else(|| panic!("raw value in {line:?}"));
    let volts = format!("{}.{} V", raw / 10, raw % 10);
    assert_eq!(
        line.trim(),
        format!("present_voltage = {volts} (raw {raw})")
    );

    // Torque off: the goal is written, and the user is told it won't move.
    assert!(sim
        .run(&["write", "--id", "2", "torque_enable", "0"])
        .status
        .success());
    let out = sim.run(&["write", "--id", "2", "goal_position", "2100"]);
    assert_eq!(out.status.code(), Some(0));
    let err = stderr(&out);
    assert!(err.contains("warning: torque is off on servo 2"), "{err}");
    assert!(err.contains("torque_enable 1"), "{err}");
    // With the torque on, no warning.
    assert!(sim
        .run(&["write", "--id", "2", "torque_enable", "1"])
        .status
        .success());
    let out = sim.run(&["write", "--id", "2", "goal_position", "2100"]);
    assert!(
        out.status.success() && out.stderr.is_empty(),
        "{}",
        stderr(&out)
    );

    // The arm runs at 1 Mbps: nobody answers at 500 kbps.
    let out = sim.run(&["scan", "--baud", "500000"]);
    assert_eq!(out.status.code(), Some(1), "a problem found");
    let err = stderr(&out);
    assert!(
        err.contains("no servo answered") && err.contains("--all-bauds"),
        "{err}"
    );

    // Another program holds the port (exclusive, as serial tools open it).
    let held = hold_exclusively(sim.port());
    let out = if is_root() {
        // Root ignores exclusive mode: try as `nobody`, who may open the pty.
        let pty = std::fs::canonicalize(sim.port()).expect("the link's pty");
        let opened = Command::new("chmod").arg("666").arg(&pty).status();
        assert!(opened.is_ok_and(|s| s.success()));
        servobus_unprivileged(&repo(""), &["ping", "--id", "1", "--port", sim.port()])
    } else {
        sim.run(&["ping", "--id", "1"])
    };
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("the port is busy") && err.contains("close it and retry"),
        "{err}"
    );
    assert_eq!(err.matches("busy").count(), 1, "{err}");
    drop(held);
    assert!(
        sim.run(&["ping", "--id", "1"]).status.success(),
        "free again"
    );

    sim.stop();
    let _ = std::fs::remove_dir_all(&dir);
}

/// Opens `path` and sets exclusive mode (`TIOCEXCL`): other opens then fail
/// with "busy" until the returned file is closed.
fn hold_exclusively(path: &str) -> std::fs::File {
    use std::os::unix::io::AsRawFd;
    let file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)
        .expect("open the pty");
    // SAFETY: TIOCEXCL takes no argument; the descriptor is open.
    let done = unsafe { libc::ioctl(file.as_raw_fd(), libc::TIOCEXCL) };
    assert_eq!(done, 0, "TIOCEXCL");
    file
}
