//! A simulated robot for the tests: `servobus sim` on a pty in wall-clock
//! time, or one bus of simulated servos in virtual time.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use servobus_driver::{Bus, ManualClock};
use servobus_runtime::bus_settings;
use servobus_runtime::config::Robot;
use servobus_sim::{Faults, SimBus};

use super::{arg, repo, stdout, write_file, BIN};

/// A truth file's header and rows (the time, then every joint's angle).
pub fn read_truth(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).expect("the truth file");
    let mut lines = text.lines();
    let header = lines.next().expect("a header").split(',');
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().expect("a number")).collect())
        .collect();
    (header.map(str::to_owned).collect(), rows)
}

/// The first bus of `robot` as `servobus sim` serves it, with `faults`, on
/// a virtual clock: the simulator (to look into and to fault) and the
/// driver's bus on it.
pub fn virtual_bus(robot: &Robot, faults: Faults) -> (SimBus, Bus<SimBus>) {
    let cfg = &robot.buses[0];
    let clock = ManualClock::new();
    let servos = servobus_robot::sim::bus_servos(robot, cfg).expect("servos");
    let sim = SimBus::new(clock.clone(), cfg.baud)
        .with_servos(servos)
        .with_faults(faults);
    let bus = Bus::new(sim.clone(), bus_settings(cfg));
    (sim, bus)
}

/// The simulator process; killed when dropped (also when a check fails).
pub struct Sim {
    child: Child,
    /// The symbolic link to the pty.
    pub link: PathBuf,
    /// When it said it was serving: the time 0 of its hand, near enough.
    pub started: Instant,
}

impl Sim {
    /// Starts `servobus sim` for the SO-101 arm with a link in `dir`.
    pub fn start(dir: &Path) -> Sim {
        Sim::start_with(dir, &[])
    }

    /// Like [`Sim::start`], with more arguments for `servobus sim`.
    pub fn start_with(dir: &Path, extra: &[&str]) -> Sim {
        Sim::start_robot(dir, &repo("configs/robots/so101.yaml"), 6, extra)
    }

    /// Starts `servobus sim` for `robot` (a file with `servos` servos) with
    /// a link in `dir` and more arguments `extra`.
    pub fn start_robot(dir: &Path, robot: &Path, servos: usize, extra: &[&str]) -> Sim {
        let link = dir.join("bus");
        let mut child = Command::new(BIN)
            .args(["sim", "--robot"])
            .arg(robot)
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
        let line = rx.recv_timeout(Duration::from_secs(60));
        let mut sim = Sim {
            child,
            link,
            started: Instant::now(),
        };
        let line = line.unwrap_or_else(|_| {
            let _ = sim.child.kill();
            panic!("servobus sim did not say it was serving");
        });
        assert_eq!(
            line.trim(),
            format!("serving {servos} servos on {}", sim.link.display())
        );
        sim
    }

    /// Starts `servobus sim` for `robot` (`servos` servos) with the
    /// arguments `extra` and a hand that plays `hand` (written to
    /// `hand.yaml` in `dir`); the truth goes to `truth.csv` in `dir`. The
    /// simulator and the truth file.
    pub fn start_hand(
        dir: &Path,
        robot: &Path,
        servos: usize,
        hand: &str,
        extra: &[&str],
    ) -> (Sim, PathBuf) {
        let hand = write_file(dir, "hand.yaml", hand);
        let truth = dir.join("truth.csv");
        let body = ["--hand", arg(&hand), "--truth", arg(&truth)];
        let sim = Sim::start_robot(dir, robot, servos, &[extra, &body].concat());
        (sim, truth)
    }

    /// Waits until the simulator has run `s` seconds.
    pub fn wait_until(&self, s: f64) {
        let at = self.started + Duration::from_secs_f64(s);
        std::thread::sleep(at.saturating_duration_since(Instant::now()));
    }

    /// The path to open.
    pub fn port(&self) -> &str {
        self.link.to_str().expect("utf-8 path")
    }

    /// The arguments `COMMAND --robot configs/robots/so101.yaml --port PORT
    /// MORE`: a robot command on this simulator's SO-101 (the path is
    /// relative to the repository, where the commands run).
    pub fn arm_args<'a>(&'a self, command: &[&'a str], more: &[&'a str]) -> Vec<&'a str> {
        let arm = [
            "--robot",
            "configs/robots/so101.yaml",
            "--port",
            self.port(),
        ];
        [command, &arm[..], more].concat()
    }

    /// Runs `servobus ARGS --port PORT --latency-us 10000` against this
    /// simulator. The latency is generous because the simulator runs in
    /// wall-clock time and its process may be scheduled milliseconds late
    /// on a loaded machine; nothing here measures time.
    pub fn run(&self, args: &[&str]) -> Output {
        self.on_port(args, &["--latency-us", "10000"])
    }

    /// `servobus ARGS --port PORT MORE` against this simulator.
    fn on_port(&self, args: &[&str], more: &[&str]) -> Output {
        Command::new(BIN)
            .args(args)
            .args(["--port", self.port()])
            .args(more)
            .current_dir(repo(""))
            .output()
            .expect("run servobus")
    }

    /// Runs `servobus ARGS --port PORT` against this simulator: a robot
    /// command, whose deadlines come from the robot file.
    pub fn robot_command(&self, args: &[&str]) -> Output {
        self.on_port(args, &[])
    }

    /// [`Sim::robot_command`], which must succeed: its standard output.
    pub fn robot_ok(&self, args: &[&str]) -> String {
        stdout(&super::succeeded(self.robot_command(args), args))
    }

    /// [`Sim::run`], which must succeed: its standard output.
    pub fn ok(&self, args: &[&str]) -> String {
        stdout(&super::succeeded(self.run(args), args))
    }

    /// `servobus scan ARGS --port PORT --latency-us 3000`, which must
    /// succeed: the pty's own allowance rather than [`Sim::run`]'s 10 ms,
    /// because a scan waits out the deadline of each of the 248 absent IDs:
    /// 1 s instead of 2.7 s. A loaded machine may hide a servo from one
    /// pass: the caller scans again then.
    pub fn scan(&self, args: &[&str]) -> String {
        let args = [&["scan"][..], args].concat();
        let out = self.on_port(&args, &["--latency-us", "3000"]);
        stdout(&super::succeeded(out, &args))
    }

    /// Register `register` of servo `id`, as `servobus read --json` gets it.
    pub fn read(&self, id: &str, register: &str) -> i64 {
        let out = self.ok(&["read", "--id", id, register, "--json"]);
        let v: serde_json::Value = serde_json::from_str(out.trim()).expect("read --json");
        v["value"]
            .as_i64()
            .unwrap_or_else(|| panic!("a value in {v}"))
    }

    /// Stops the simulator as a user would (SIGTERM) and waits for it.
    pub fn stop(mut self) {
        if !super::signal(&self.child, "TERM") {
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
