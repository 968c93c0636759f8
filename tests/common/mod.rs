//! Helpers shared by the end-to-end tests: the `servobus` binary and a
//! simulated robot served by `servobus sim` on a pty.
#![allow(dead_code)]

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// The `servobus` binary under test.
pub const BIN: &str = env!("CARGO_BIN_EXE_servobus");

/// A file of the repository, by its path from the root.
pub fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// Runs `servobus ARGS` from the repository's root.
pub fn servobus(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the servobus binary runs")
}

/// Runs `servobus ARGS`, which must succeed, and parses its one JSON object.
pub fn servobus_json(args: &[&str]) -> serde_json::Value {
    let out = servobus(args);
    assert!(
        out.status.success(),
        "servobus {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

/// The number `v[key]`.
pub fn num(v: &serde_json::Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("`{key}` is a number in {v}"))
}

/// A fresh scratch directory for one test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("servobus-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// The simulator process; killed when dropped (also when a check fails).
pub struct Sim {
    child: Child,
    /// The symbolic link to the pty.
    pub link: PathBuf,
}

impl Sim {
    /// Starts `servobus sim` for the SO-101 arm with a link in `dir`.
    pub fn start(dir: &Path) -> Sim {
        Sim::start_with(dir, &[])
    }

    /// Like [`Sim::start`], with more arguments for `servobus sim`.
    pub fn start_with(dir: &Path, extra: &[&str]) -> Sim {
        let link = dir.join("bus");
        let robot = repo("configs/robots/so101.yaml");
        let mut child = Command::new(BIN)
            .args(["sim", "--robot"])
            .arg(&robot)
            .arg("--link")
            .arg(&link)
            .args(extra)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start servobus sim");
        let stdout = child.stdout.take().expect("sim stdout");
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let mut line = String::new();
            let _ = BufReader::new(stdout).read_line(&mut line);
            let _ = tx.send(line);
        });
        let mut sim = Sim { child, link };
        let line = rx
            .recv_timeout(Duration::from_secs(60))
            .unwrap_or_else(|_| {
                let _ = sim.child.kill();
                panic!("servobus sim did not say it was serving");
            });
        assert_eq!(
            line.trim(),
            format!("serving 6 servos on {}", sim.link.display())
        );
        sim
    }

    /// The path to open.
    pub fn port(&self) -> &str {
        self.link.to_str().expect("utf-8 path")
    }

    /// Stops the simulator as a user would (SIGTERM) and waits for it.
    pub fn stop(mut self) {
        let pid = self.child.id().to_string();
        let sent = Command::new("kill").args(["-TERM", &pid]).status();
        if !sent.is_ok_and(|s| s.success()) {
            let _ = self.child.kill();
        }
        let _ = self.child.wait();
    }
}

impl Drop for Sim {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}
