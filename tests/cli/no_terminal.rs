//! No terminal assumed: `servobus monitor` and `play --monitor` run in a
//! session of their own (`setsid`: no controlling terminal) with standard
//! input and output that are no terminal, as under cron, CI or `ssh`
//! without `-t`. The monitor falls back to JSON lines and says so; `play
//! --monitor` refuses before anything moves (every servo's torque is still
//! off on the simulator afterwards); nothing panics and no escape code is
//! written into the redirected output.

use crate::common;

use std::os::unix::process::CommandExt;
use std::process::{Command, Output, Stdio};

use common::{exited, repo, scratch, Sim, BIN};

/// Runs `servobus ARGS` without a terminal: a new session (no controlling
/// terminal, so `/dev/tty` cannot be opened), stdin from `/dev/null`,
/// stdout and stderr piped.
fn without_terminal(args: &[&str]) -> Output {
    let mut command = Command::new(BIN);
    command
        .args(args)
        .current_dir(repo(""))
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    // SAFETY: setsid is async-signal-safe and touches no memory of the
    // parent; it runs in the child between fork and exec.
    unsafe {
        command.pre_exec(|| {
            if libc::setsid() == -1 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    command.output().expect("run servobus")
}

/// Neither a panic nor an escape code in what `out` wrote.
fn plain(out: &Output) {
    for (name, bytes) in [("stdout", &out.stdout), ("stderr", &out.stderr)] {
        let text = String::from_utf8_lossy(bytes);
        assert!(!text.contains('\x1b'), "escape code in {name}: {text:?}");
        assert!(!text.contains("panicked"), "a panic in {name}: {text}");
    }
}

#[test]
fn monitor_without_a_terminal_prints_json_lines_and_says_so() {
    let dir = scratch("no-terminal-monitor");
    let sim = Sim::start(&dir);
    let out = without_terminal(&sim.arm_args(&["monitor"], &["--count", "3"]));
    let (stdout, stderr) = exited(&out, 0);
    plain(&out);
    assert!(
        stderr.contains("no terminal") && stderr.contains("JSON line"),
        "{stderr}"
    );
    let frames: Vec<serde_json::Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON object per line"))
        .collect();
    assert_eq!(frames.len(), 3, "{stdout}");
    // The simulator is a process of its own on a real pseudo-terminal: on
    // a loaded host one refresh may miss a reply, which the monitor reports
    // truthfully. What must hold is that every servo is there, in every
    // frame, and that each answered in some frame.
    let mut answered = [false; 6];
    for frame in &frames {
        let servos = frame["servos"].as_array().expect("servos");
        assert_eq!(servos.len(), 6, "{frame}");
        for (slot, servo) in answered.iter_mut().zip(servos) {
            assert!(servo["present"].is_boolean(), "{servo}");
            *slot |= servo["present"] == true;
        }
    }
    assert!(
        answered.iter().all(|&a| a),
        "a servo never answered: {stdout}"
    );
    sim.stop();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn ctrl_c_ends_a_monitor_without_a_terminal_after_a_whole_line() {
    let dir = scratch("no-terminal-monitor-int");
    let sim = Sim::start(&dir);
    let args = sim.arm_args(&["monitor"], &["--rate", "50"]);
    let mut monitor = common::Running::start_bin(std::path::Path::new(BIN), Some(&repo("")), &args);
    // A few refreshes, then Ctrl-C (SIGINT) as a shell sends it.
    monitor.wait_for(false, "a first JSON line", |l| l.contains("\"servos\""));
    monitor.wait_for(false, "a second JSON line", |l| l.contains("\"servos\""));
    monitor.interrupt();
    let (status, stdout, stderr) = monitor.finish();
    // The watch's own end: no servo missing or flagged, so 0.
    assert_eq!(status.code(), Some(0), "{status}: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    // Every line whole: the last one too.
    let mut frames = 0;
    for line in stdout.lines() {
        let frame: serde_json::Value =
            serde_json::from_str(line).expect("one whole JSON object per line");
        assert!(frame["servos"].is_array(), "{frame}");
        frames += 1;
    }
    assert!(frames >= 2, "{stdout}");
    sim.stop();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn play_monitor_without_a_terminal_refuses_before_any_torque() {
    let dir = scratch("no-terminal-play");
    let sim = Sim::start(&dir);
    let out =
        without_terminal(&sim.arm_args(&["play", "configs/motions/arm-wave.yaml"], &["--monitor"]));
    let (stdout, stderr) = exited(&out, 2);
    plain(&out);
    assert!(stdout.is_empty(), "nothing planned or shown: {stdout}");
    assert!(
        stderr.contains("--monitor needs a terminal") && stderr.contains("nothing was moved"),
        "{stderr}"
    );
    // The simulator's servos start with the torque off: still off.
    for id in 1..=6 {
        let id = id.to_string();
        assert_eq!(sim.read(&id, "torque_enable"), 0, "servo {id}");
    }
    sim.stop();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn play_progress_without_a_terminal_is_plain_lines() {
    let out = without_terminal(&[
        "play",
        "configs/motions/arm-wave.yaml",
        "--robot",
        "configs/robots/so101.yaml",
        "--fast",
    ]);
    let (stdout, _) = exited(&out, 0);
    plain(&out);
    assert!(stdout.contains("completed"), "{stdout}");
}
