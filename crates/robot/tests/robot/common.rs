//! What the tests share: the repository's files, a simulated bus on a
//! pseudo-terminal served on a thread, a run stopped on command; robot and
//! motion files loaded and the telemetry of a virtual-time run recorded
//! (for the calibration, teaching, body and live tests).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use servobus_robot::config::{
    load_motion, load_robot, plan_motion, Robot as RobotFile, RobotOptions,
};
use servobus_robot::sim::{Mounting, SimRobot};
use servobus_robot::{Connection, Report, Robot, RunOptions, Telemetry};
use servobus_runtime::{Fault, VirtualRun};
use servobus_sim::PtyServer;
use servobus_trajectory::{JointState, Trajectory};

// The shipped files and scratch files, as the configuration's tests have
// them.
#[path = "../../../config/tests/common/mod.rs"]
mod files;
pub use files::{config, temp_path};

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

/// A robot file under `configs/robots/`.
pub fn robot(name: &str) -> RobotFile {
    load_robot(&config(&format!("robots/{name}")), &RobotOptions::default())
        .expect("robot file loads")
}

/// A robot file under `configs/robots/` with the calibration file
/// `calibration` applied.
pub fn calibrated(name: &str, calibration: &std::path::Path) -> RobotFile {
    let options = RobotOptions::default().calibration(Some(calibration));
    load_robot(&config(&format!("robots/{name}")), &options).expect("the calibration applies")
}

/// A motion under `configs/motions/`, planned, with its robot.
pub fn motion(name: &str) -> (Trajectory, RobotFile) {
    let (m, r) = load_motion(&config(&format!("motions/{name}")), None).expect("motion loads");
    let t = plan_motion(&m, &r).expect("motion plans");
    (t, r)
}

/// Where `path` starts, per joint in the robot's units.
pub fn start_pose(robot: &RobotFile, path: &Trajectory) -> Vec<f64> {
    let mut start = vec![JointState::default(); robot.joint_count()];
    path.sample(0.0, &mut start);
    start
        .iter()
        .map(|s| robot.units.from_rad(s.position))
        .collect()
}

/// Run options without telemetry, for tests that read only the report.
pub fn quiet() -> RunOptions {
    RunOptions {
        telemetry_capacity: 0,
        ..RunOptions::default()
    }
}

/// Every telemetry cycle sample of a run, collected by stepping it.
pub struct Recorded {
    /// `(cycle, joint, commanded, error, measured)` in report units.
    pub rows: Vec<(u64, usize, f64, f64, Option<f64>)>,
    /// Faults published.
    pub faults: Vec<Fault>,
}

/// Steps `run` until it ends or `max` cycles pass, calling `each(cycle)`
/// before every step, and records the telemetry.
pub fn record<T: servobus_driver::Transport>(
    run: &mut VirtualRun<T>,
    max: u64,
    mut each: impl FnMut(u64),
) -> Recorded {
    let rx = run.telemetry();
    let mut rec = Recorded {
        rows: Vec::new(),
        faults: Vec::new(),
    };
    let drain = |rec: &mut Recorded| {
        while let Ok(m) = rx.try_recv() {
            match m {
                Telemetry::Cycle(c) => {
                    for j in c.joints() {
                        rec.rows
                            .push((c.cycle, j.joint, j.commanded, j.error, j.measured));
                    }
                }
                Telemetry::Fault(f) => rec.faults.push(f),
                _ => {}
            }
        }
    };
    for _ in 0..max {
        each(run.cycle());
        let going = run.step();
        drain(&mut rec);
        if !going {
            break;
        }
    }
    rec
}
