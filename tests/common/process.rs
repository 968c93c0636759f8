//! A `servobus` process the test talks to while it runs: its output lines
//! collected as they come, signals sent as a terminal sends them.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::BIN;

/// Generous: a loaded machine may be slow to start or to answer.
const PATIENCE: Duration = Duration::from_secs(60);

/// Sends signal `sig` (a name such as `INT`) to `child`, as `kill` does;
/// whether it was sent.
pub fn signal(child: &Child, sig: &str) -> bool {
    let sent = Command::new("kill")
        .args([format!("-{sig}"), child.id().to_string()])
        .status();
    sent.is_ok_and(|s| s.success())
}

/// A running `servobus`, its output lines collected as they come; killed
/// when dropped.
pub struct Running {
    child: Child,
    stdout: Receiver<String>,
    stderr: Receiver<String>,
    seen_out: Arc<Mutex<Vec<String>>>,
    seen_err: Arc<Mutex<Vec<String>>>,
}

/// The lines of `stream`, sent as they come and kept.
fn lines(
    stream: impl std::io::Read + Send + 'static,
) -> (Receiver<String>, Arc<Mutex<Vec<String>>>) {
    let (tx, rx) = mpsc::channel();
    let seen = Arc::new(Mutex::new(Vec::new()));
    let keep = Arc::clone(&seen);
    std::thread::spawn(move || {
        for line in BufReader::new(stream).lines().map_while(Result::ok) {
            keep.lock().expect("lines").push(line.clone());
            let _ = tx.send(line);
        }
    });
    (rx, seen)
}

impl Running {
    /// Starts `servobus ARGS`.
    pub fn start(args: &[&str]) -> Running {
        Running::start_bin(std::path::Path::new(BIN), None, args)
    }

    /// Starts the `servobus` binary at `bin` (an installed one, say) with
    /// `ARGS`, in `dir` (the test's own directory when `None`).
    pub fn start_bin(
        bin: &std::path::Path,
        dir: Option<&std::path::Path>,
        args: &[&str],
    ) -> Running {
        let mut command = Command::new(bin);
        if let Some(dir) = dir {
            command.current_dir(dir);
        }
        let mut child = command
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start servobus");
        let (stdout, seen_out) = lines(child.stdout.take().expect("stdout"));
        let (stderr, seen_err) = lines(child.stderr.take().expect("stderr"));
        Running {
            child,
            stdout,
            stderr,
            seen_out,
            seen_err,
        }
    }

    /// Waits for a line of stderr (`err`) or stdout that `want` accepts.
    pub fn wait_for(&mut self, err: bool, what: &str, want: impl Fn(&str) -> bool) -> String {
        let deadline = Instant::now() + PATIENCE;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let rx = if err { &self.stderr } else { &self.stdout };
            match rx.recv_timeout(left) {
                Ok(line) if want(&line) => return line,
                Ok(_) => {}
                Err(_) => {
                    let _ = self.child.kill();
                    panic!(
                        "no {what} within {PATIENCE:?}; stdout {:?} stderr {:?}",
                        self.seen_out.lock().expect("lines"),
                        self.seen_err.lock().expect("lines")
                    );
                }
            }
        }
    }

    /// Ctrl-C, as the terminal sends it.
    pub fn interrupt(&self) {
        assert!(signal(&self.child, "INT"), "kill -INT failed");
    }

    /// Waits for the exit; returns the status, stdout and stderr.
    pub fn finish(mut self) -> (ExitStatus, String, String) {
        let deadline = Instant::now() + PATIENCE;
        let status = loop {
            if let Some(s) = self.child.try_wait().expect("wait") {
                break s;
            }
            if Instant::now() > deadline {
                let _ = self.child.kill();
                panic!("servobus did not end within {PATIENCE:?}");
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        // The readers end with the pipes; give them a moment to drain.
        let drained = Instant::now() + Duration::from_secs(10);
        while Instant::now() < drained
            && (self.stdout.recv_timeout(Duration::from_millis(50)).is_ok()
                || self.stderr.recv_timeout(Duration::from_millis(50)).is_ok())
        {}
        let out = self.seen_out.lock().expect("lines").join("\n");
        let err = self.seen_err.lock().expect("lines").join("\n");
        (status, out, err)
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}
