//! What the tests share: the repository's files, a simulated bus on a
//! pseudo-terminal served on a thread, a run stopped on command; robot and
//! motion files loaded and the telemetry of a virtual-time run recorded
//! (for the calibration, teaching, body and live tests).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use servobus_robot::config::{load_robot, Robot as RobotFile, RobotOptions};
use servobus_robot::sim::{Mounting, SimRobot};
use servobus_robot::{Connection, Play, Report, Robot, Telemetry};
use servobus_sim::PtyServer;

// The shipped files and scratch files, as the configuration's tests have
// them.
#[path = "../../../config/tests/common/mod.rs"]
mod files;
pub use files::{config, temp_path};

// Robot files, planned motions and recorded telemetry, as the runtime's
// tests have them.
#[path = "../../../runtime/tests/common/runs.rs"]
mod runs;
pub use runs::{motion, quiet, record, robot, start_pose};

/// A file of the repository.
pub fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
}

/// The first bus of `robot` served on a pty (the servos mounted as
/// `mounting` says, or bare shafts), until dropped.
pub struct Pty {
    /// The terminal to open.
    pub path: String,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Pty {
    /// Serves `robot`'s first bus.
    pub fn serve(robot: &servobus_robot::config::Robot, mounting: Option<Mounting>) -> Pty {
        let mut builder = SimRobot::builder(robot);
        if let Some(m) = mounting {
            builder = builder.mounting(m);
        }
        let servos = builder
            .servos(&robot.buses[0])
            .expect("the servos simulate");
        let mut server = PtyServer::open(robot.buses[0].baud, servos).expect("a pty");
        let path = server.path().to_string_lossy().into_owned();
        let stop = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&stop);
        let thread = std::thread::spawn(move || {
            server.serve(&flag).expect("the pty serves");
        });
        Pty {
            path,
            stop,
            thread: Some(thread),
        }
    }
}

impl Drop for Pty {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Plays `what` on `connection` with its own options to its end, and
/// returns the report.
pub fn play_to_end(connection: Connection, what: impl Into<Play>) -> Report {
    let options = connection.options();
    connection
        .play(what, options)
        .expect("starts")
        .join()
        .expect("a report")
}

/// Plays arm-wave on `connection`, stops it after 20 cycles (however slow
/// the machine), and returns the report.
pub fn stopped_after_some_cycles(robot: &Robot, connection: Connection) -> Report {
    let motion = robot.motion("arm-wave").expect("the motion");
    let options = connection.options();
    let run = connection.play(&motion, options).expect("starts");
    let telemetry = run.telemetry();
    let mut cycles = 0;
    while cycles < 20 {
        match telemetry.recv_timeout(Duration::from_secs(30)) {
            Ok(Telemetry::Cycle(_)) => cycles += 1,
            Ok(_) => {}
            Err(e) => panic!("the run sends telemetry: {e}"),
        }
    }
    run.stop().expect("the run takes the command");
    run.join().expect("a report")
}

/// A robot file under `configs/robots/` with the calibration file
/// `calibration` applied.
pub fn calibrated(name: &str, calibration: &std::path::Path) -> RobotFile {
    let options = RobotOptions::default().calibration(Some(calibration));
    load_robot(&config(&format!("robots/{name}")), &options).expect("the calibration applies")
}
