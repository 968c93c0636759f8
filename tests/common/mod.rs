//! Helpers shared by the end-to-end tests: the `servobus` binary run with
//! arguments, its output read, files for it written, and a simulated robot
//! served by `servobus sim` on a pty ([`Sim`]) or in virtual time
//! ([`virtual_bus`]).
#![allow(dead_code)]

mod process;
mod sim;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

// Not every test uses every helper.
#[allow(unused_imports)]
pub use process::{signal, Running};
#[allow(unused_imports)]
pub use sim::{read_truth, virtual_bus, Sim};

/// The `servobus` binary under test.
pub const BIN: &str = env!("CARGO_BIN_EXE_servobus");

/// A file of the repository, by its path from the root.
pub fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// The names of the joints of the robot file `path`, in its order (read
/// from the YAML here, not by servobus).
pub fn joint_names(path: &str) -> Vec<String> {
    let text = std::fs::read_to_string(repo(path)).expect("a robot file");
    let robot: serde_yaml::Value = serde_yaml::from_str(&text).expect("YAML");
    let buses = robot["buses"].as_sequence().expect("buses");
    let joints = buses
        .iter()
        .flat_map(|b| b["joints"].as_sequence().expect("joints"));
    let names = joints.map(|j| j["name"].as_str().expect("a joint's name").to_owned());
    names.collect()
}

/// The SO-101's joints, in its robot file's order.
pub const SO101_JOINTS: [&str; 6] = [
    "shoulder_pan",
    "shoulder_lift",
    "elbow_flex",
    "wrist_flex",
    "wrist_roll",
    "gripper",
];

/// A path as the `&str` a command line takes.
pub fn arg(path: &Path) -> &str {
    path.to_str().expect("a UTF-8 path")
}

/// Runs `servobus ARGS` from the repository's root.
pub fn servobus(args: &[&str]) -> Output {
    servobus_in(&repo(""), args)
}

/// Runs `servobus ARGS` in `dir`.
pub fn servobus_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the servobus binary runs")
}

/// Starts `servobus ARGS` in `dir` with stdin and stdout null and stderr
/// piped.
pub fn spawn_stderr_piped<S: AsRef<std::ffi::OsStr>>(dir: &Path, args: &[S]) -> Child {
    Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the servobus binary runs")
}

/// `follow --robot so101 --leader-hand so101-hand --seconds SECONDS`, then
/// `more`: the SO-101 following the built-in hand.
pub fn follow_hand<'a>(seconds: &'a str, more: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "follow",
        "--robot",
        "so101",
        "--leader-hand",
        "so101-hand",
        "--seconds",
        seconds,
    ];
    args.extend_from_slice(more);
    args
}

/// Runs `cargo metadata --format-version 1 FLAGS --manifest-path MANIFEST`,
/// which must succeed, and parses its JSON.
pub fn cargo_metadata(manifest: &Path, flags: &[&str]) -> serde_json::Value {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| env!("CARGO").into());
    let out = Command::new(cargo)
        .args(["metadata", "--format-version", "1"])
        .args(flags)
        .arg("--manifest-path")
        .arg(manifest)
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON")
}

/// Runs `servobus ARGS` from the repository's root; it must succeed.
pub fn servobus_ok(args: &[&str]) -> Output {
    succeeded(servobus(args), args)
}

/// An outside program a test needs is missing (`why` says which and how to
/// get it): under `CI=true` the test fails, elsewhere it is skipped, said
/// on stderr.
pub fn missing_outside<T>(why: &str) -> Option<T> {
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("{why} (required under CI=true)");
    }
    eprintln!("\n*** SKIPPED: {why} ***\n");
    None
}

/// `out`, of `servobus ARGS`, which must have succeeded.
pub fn succeeded(out: Output, args: &[&str]) -> Output {
    assert!(
        out.status.success(),
        "servobus {args:?} failed: {}{}",
        stdout(&out),
        stderr(&out)
    );
    out
}

/// Runs `servobus ARGS`, which must succeed, and parses its one JSON object.
pub fn servobus_json(args: &[&str]) -> serde_json::Value {
    json(&servobus_ok(args))
}

/// The one JSON object a command printed.
pub fn json(out: &Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("not one JSON object ({e}): {}{}", stdout(out), stderr(out)))
}

/// What a command printed on its standard output.
pub fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// What a command printed on its standard error.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Checks that a command exited with `code`; returns its stdout and stderr.
pub fn exited(out: &Output, code: i32) -> (String, String) {
    let (o, e) = (stdout(out), stderr(out));
    assert_eq!(out.status.code(), Some(code), "stdout {o}\nstderr {e}");
    (o, e)
}

/// Runs `servobus ARGS`, which must fail (any exit code but 0); returns
/// its standard error.
pub fn servobus_fails(args: &[&str]) -> String {
    let out = servobus(args);
    assert!(!out.status.success(), "servobus {args:?} succeeded");
    stderr(&out)
}

/// The one-line error of a command that must exit with `code`.
pub fn error(out: &Output, code: i32) -> String {
    let (_, err) = exited(out, code);
    assert!(err.starts_with("error: "), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    err
}

/// Checks that `text` contains every one of `words`.
pub fn says(text: &str, words: &[&str]) {
    for w in words {
        assert!(text.contains(w), "{text:?} should say {w:?}");
    }
}

/// The number `v[key]`.
pub fn num(v: &serde_json::Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("`{key}` is a number in {v}"))
}

/// The text of the repository's file `path` with each `(from, to)` edit
/// made once; each `from` must be there (the test says so if the file
/// changed under it).
pub fn edited(path: &str, edits: &[(&str, &str)]) -> String {
    let mut text = std::fs::read_to_string(repo(path)).expect("a shipped file");
    for (from, to) in edits {
        assert!(text.contains(from), "{path} no longer has {from:?}");
        text = text.replacen(from, to, 1);
    }
    text
}

/// Writes `text` to the file `name` in `dir` (made if missing).
pub fn write_file(dir: &Path, name: &str, text: &str) -> PathBuf {
    std::fs::create_dir_all(dir).expect("a folder for the file");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("the file is written");
    path
}

/// Writes `text` to the file `name` in `dir`, a folder of its own under
/// Cargo's temporary directory for tests.
pub fn temp_file(dir: &str, name: &str, text: &str) -> PathBuf {
    write_file(
        &Path::new(env!("CARGO_TARGET_TMPDIR")).join(dir),
        name,
        text,
    )
}

/// A robot of one joint `a` at 100 Hz: -100..100 deg, 90 deg/s, 180
/// deg/s^2 and no jerk limit, so rest-to-rest moves are trapezoids.
pub const ONE_JOINT: &str = "\
name: one
rate: 100
buses:
  - name: bus
    joints:
      - {name: a, id: 1, model: sts3215, min: -100, max: 100, max_velocity: 90, max_acceleration: 180}
";

/// Writes [`ONE_JOINT`] as `robot.yaml` and `motion` as `name` into `dir`
/// (as [`temp_file`]); the motion's path.
pub fn one_joint_motion(dir: &str, name: &str, motion: &str) -> PathBuf {
    temp_file(dir, "robot.yaml", ONE_JOINT);
    temp_file(dir, name, motion)
}

/// A fresh scratch directory for one test: `servobus-<name>-<pid>` in the
/// temporary directory (where a test run as `nobody` can reach it). Those
/// of test runs that have ended are removed first, once a run.
pub fn scratch(name: &str) -> PathBuf {
    static SWEPT: std::sync::Once = std::sync::Once::new();
    SWEPT.call_once(sweep_ended_runs);
    let dir = std::env::temp_dir().join(format!("servobus-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// Removes the `servobus-<name>-<pid>` scratch entries of processes that
/// are gone (Linux: their `/proc/<pid>` is missing); nothing where there
/// is no `/proc` to ask.
fn sweep_ended_runs() {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(std::env::temp_dir()) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name
            .to_str()
            .and_then(|n| n.strip_prefix("servobus-"))
            .and_then(|rest| rest.rsplit_once('-'))
            .and_then(|(_, pid)| pid.parse::<u32>().ok())
        else {
            continue;
        };
        if pid == std::process::id() || Path::new(&format!("/proc/{pid}")).exists() {
            continue;
        }
        let path = entry.path();
        let _ = if path.is_dir() {
            std::fs::remove_dir_all(&path)
        } else {
            std::fs::remove_file(&path)
        };
    }
}

/// Whether the tests run as root (who may open anything and use any
/// scheduling policy).
pub fn is_root() -> bool {
    // SAFETY: geteuid has no preconditions.
    unsafe { libc::geteuid() == 0 }
}

/// Runs `servobus ARGS` in `dir` without privileges: its real-time
/// priority limit (`RLIMIT_RTPRIO`) is 0, so SCHED_FIFO is refused, and when
/// the tests run as root it runs as `nobody` (uid and gid 65534, no
/// groups), which also drops root's capabilities (CAP_SYS_NICE, CAP_DAC_*).
/// Arranged in the child between fork and exec: no outside program needed.
pub fn servobus_unprivileged(dir: &Path, args: &[&str]) -> Output {
    use std::os::unix::process::CommandExt;
    let root = is_root();
    let mut command = Command::new(BIN);
    command.args(args).current_dir(dir);
    // SAFETY: between fork and exec the closure calls only setrlimit,
    // setgroups, setgid and setuid (async-signal-safe system calls) and
    // allocates nothing.
    unsafe {
        command.pre_exec(move || {
            let none = libc::rlimit {
                rlim_cur: 0,
                rlim_max: 0,
            };
            if libc::setrlimit(libc::RLIMIT_RTPRIO, &none) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            if root
                && (libc::setgroups(0, std::ptr::null()) != 0
                    || libc::setgid(65534) != 0
                    || libc::setuid(65534) != 0)
            {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    command
        .output()
        .expect("the servobus binary runs unprivileged")
}
