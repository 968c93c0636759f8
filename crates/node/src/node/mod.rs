//! The Zenoh session of a serving robot: opens it safely (loopback,
//! no multicast scouting unless a config file turns it on), declares the
//! robot's keys, and relays between them and the running loop.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use servobus_robot::config::Units;
use servobus_robot::{Command, Report, Run, Telemetry};
use zenoh::bytes::Encoding;
use zenoh::Wait;

use crate::prefix;

mod relay;
mod session;
mod state;

use relay::{take_command, take_target, Inputs, Motion};

use session::zerr;
pub use session::{
    group_command_key, group_member_key, open_peer, open_session, NodeConfig, NodeError,
    DEFAULT_LISTEN,
};
use state::{publish_state, Ros2, Watch};

/// Turns the motion of a `play` command (a name, a file or YAML text) into
/// the command that plays it; the node's owner knows the robot and plans.
pub type Planner = dyn Fn(&str) -> Result<Command, String> + Send + Sync;

/// The robot as the node sees it.
#[derive(Debug, Clone)]
pub struct RobotInfo {
    /// The robot's name (the key chunk after `servobus/`).
    pub name: String,
    /// Joint names, in the robot's order.
    pub joints: Vec<String>,
    /// The angle units of the robot file (targets and `state` use them).
    pub units: Units,
    /// The control rate, Hz.
    pub rate_hz: f64,
}

/// What the node reports at the end: the run's report and its own counts.
#[derive(Debug)]
pub struct Served {
    /// The run's report.
    pub report: Report,
    /// Targets taken into the stream.
    pub targets: u64,
    /// Action chunks taken into the stream.
    pub chunks: u64,
    /// Targets or commands that did not parse (never acted on).
    pub malformed: u64,
    /// Commands carried out.
    pub commands: u64,
    /// States published on `state`.
    pub states: u64,
    /// Timed `play` commands: the start cycle's measured start minus the
    /// agreed instant, s.
    pub start_offsets: Vec<f64>,
}

impl Served {
    /// The node's own counts as JSON: `targets`, `chunks`, `malformed`,
    /// `commands`, `states`, `start_offsets_s` (what `report` and
    /// `serve --json` show).
    pub fn counts(&self) -> serde_json::Value {
        serde_json::json!({
            "targets": self.targets,
            "chunks": self.chunks,
            "malformed": self.malformed,
            "commands": self.commands,
            "states": self.states,
            "start_offsets_s": self.start_offsets,
        })
    }
}

#[derive(Debug, Default)]
struct Counts {
    targets: AtomicU64,
    chunks: AtomicU64,
    malformed: AtomicU64,
    commands: AtomicU64,
}

/// What the callbacks and the telemetry loop share.
#[derive(Default)]
struct Shared {
    /// Wall-clock time of cycle 0's deadline, once the first cycle ran.
    start: Mutex<Option<SystemTime>>,
    /// Timed starts waiting to be measured: (cycle, agreed instant).
    timed: Mutex<Vec<(u64, SystemTime)>>,
    /// What `report` answers: progress while running, then the report.
    report: Mutex<String>,
    counts: Counts,
    /// Whether `stop` holds the robot (see [`relay`]).
    motion: Mutex<Motion>,
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

fn unix_ns(t: SystemTime) -> i64 {
    t.duration_since(UNIX_EPOCH)
        .map_or(0, |d| i64::try_from(d.as_nanos()).unwrap_or(i64::MAX))
}

/// Runs `run` (a live run of the facade, [`servobus_robot::Connection::live`]) as a Zenoh node on `session` until the run ends, then
/// keeps answering `report` for `linger`. See the crate docs for the keys.
///
/// # Errors
/// [`NodeError::Zenoh`] when a key cannot be declared; [`NodeError::Run`]
/// when the run cannot be joined.
pub fn serve(
    session: &zenoh::Session,
    robot: &RobotInfo,
    runner: Run,
    planner: Box<Planner>,
    config: &NodeConfig,
    linger: Duration,
) -> Result<Served, NodeError> {
    let base = prefix(&robot.name);
    let shared = Arc::new(Shared::default());
    *lock(&shared.report) = serde_json::json!({"running": true}).to_string();
    let period = 1.0 / robot.rate_hz;

    let _alive = session
        .liveliness()
        .declare_token(format!("{base}/alive"))
        .wait()
        .map_err(zerr)?;
    let _member = match &config.group {
        Some(g) => Some(
            session
                .liveliness()
                .declare_token(group_member_key(g, &robot.name))
                .wait()
                .map_err(zerr)?,
        ),
        None => None,
    };
    let state = session
        .declare_publisher(format!("{base}/state"))
        .encoding(Encoding::APPLICATION_JSON)
        .wait()
        .map_err(zerr)?;
    let _targets = {
        let to = Inputs {
            targets: runner.targets(),
            commands: runner.commands(),
        };
        let shared = Arc::clone(&shared);
        let units = robot.units;
        let started = Instant::now();
        session
            .declare_subscriber(format!("{base}/target"))
            .callback(move |sample| {
                take_target(&sample.payload().to_bytes(), &to, units, started, &shared);
            })
            .wait()
            .map_err(zerr)?
    };
    let planner: Arc<Planner> = Arc::from(planner);
    let mut command_keys = vec![format!("{base}/command")];
    if let Some(g) = &config.group {
        command_keys.push(group_command_key(g));
    }
    let mut _commands = Vec::new();
    for key in command_keys {
        let to = Inputs {
            targets: runner.targets(),
            commands: runner.commands(),
        };
        let shared = Arc::clone(&shared);
        let planner = Arc::clone(&planner);
        _commands.push(
            session
                .declare_subscriber(key)
                .callback(move |sample| {
                    take_command(
                        &sample.payload().to_bytes(),
                        &to,
                        &*planner,
                        period,
                        &shared,
                    );
                })
                .wait()
                .map_err(zerr)?,
        );
    }
    let _report = {
        let shared = Arc::clone(&shared);
        session
            .declare_queryable(format!("{base}/report"))
            .callback(move |query| {
                let text = lock(&shared.report).clone();
                let key = query.key_expr().clone();
                if let Err(e) = query
                    .reply(key, text)
                    .encoding(Encoding::APPLICATION_JSON)
                    .wait()
                {
                    eprintln!("report: the reply could not be sent: {e}");
                }
            })
            .wait()
            .map_err(zerr)?
    };
    let ros = match config.ros2_domain {
        Some(domain) => Some(Ros2::declare(session, domain, &robot.name)?),
        None => None,
    };

    let every = ((robot.rate_hz / config.state_hz.max(0.1)).round() as u64).max(1);
    let mut watch = Watch::new(robot);
    let mut states = 0u64;
    let mut offsets = Vec::new();
    let mut ros_seq = 0i64;
    for m in runner.telemetry().iter() {
        match m {
            Telemetry::Cycle(c) => {
                if c.bus == 0 {
                    // Cycle 0's deadline on the wall clock: the earliest
                    // estimate wins (a sample arrives after its cycle).
                    let now = SystemTime::now();
                    let here = now
                        .checked_sub(Duration::from_secs_f64(c.time_s.max(0.0)))
                        .unwrap_or(now);
                    let mut start = lock(&shared.start);
                    let s = match *start {
                        Some(s) if s <= here => s,
                        _ => here,
                    };
                    *start = Some(s);
                    drop(start);
                    measure_starts(
                        &shared,
                        c.cycle,
                        s,
                        c.time_s + c.lateness.as_secs_f64(),
                        &mut offsets,
                    );
                }
                if let Some(done) = watch.cycle(&c) {
                    if done.cycle % every == 0 {
                        publish_state(&state, &done)?;
                        states += 1;
                        if let Some(ros) = &ros {
                            ros_seq += 1;
                            ros.publish(&done, robot.units, ros_seq)?;
                        }
                        let progress = serde_json::json!({
                            "running": true, "cycle": done.cycle, "t": done.t,
                        });
                        *lock(&shared.report) = progress.to_string();
                    }
                }
            }
            Telemetry::Fault(f) => {
                eprintln!("fault: {f}");
                watch.faults.push(f.to_string());
            }
            Telemetry::Rejected(why) => eprintln!("refused: {why}"),
            Telemetry::Finished(_) => break,
            _ => {}
        }
    }
    let report = runner.join()?;
    let c = &shared.counts;
    let served = Served {
        targets: c.targets.load(Ordering::Relaxed),
        chunks: c.chunks.load(Ordering::Relaxed),
        malformed: c.malformed.load(Ordering::Relaxed),
        commands: c.commands.load(Ordering::Relaxed),
        states,
        start_offsets: offsets,
        report,
    };
    *lock(&shared.report) = serde_json::json!({
        "running": false,
        "report": served.report,
        "node": served.counts(),
    })
    .to_string();
    std::thread::sleep(linger);
    Ok(served)
}

/// Measures the timed starts due at `cycle`, which started `t` s after
/// `start` on the wall clock.
fn measure_starts(shared: &Shared, cycle: u64, start: SystemTime, t: f64, out: &mut Vec<f64>) {
    let mut timed = lock(&shared.timed);
    timed.retain(|&(k, at)| {
        if k > cycle {
            return true;
        }
        let began = start + Duration::from_secs_f64(t.max(0.0));
        let offset = match began.duration_since(at) {
            Ok(d) => d.as_secs_f64(),
            Err(e) => -e.duration().as_secs_f64(),
        };
        out.push(offset);
        false
    });
}
