//! The Zenoh session of a serving robot: opens it safely (loopback,
//! no multicast scouting unless a config file turns it on), declares the
//! robot's keys, and relays between them and the running loop.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use servobus_robot::config::Units;
use servobus_robot::{Command, CycleSample, Report, Run, Telemetry};

mod keys;
mod relay;
mod ros;
mod session;
mod state;
#[cfg(test)]
mod virtual_node;

use keys::Keys;
use relay::Motion;

use session::zerr;
pub use session::{
    group_command_key, group_member_key, open_peer, open_session, NodeConfig, NodeError,
    DEFAULT_LISTEN,
};
use state::{publish_state, Done, Watch};

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
    /// The robot as its file describes it, for targets that need more than
    /// names: a mobile base's velocity becomes its wheels' speeds. `None`:
    /// base targets are refused (counted as malformed).
    pub config: Option<servobus_robot::config::Robot>,
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
    /// ROS 2 `joint_trajectory` messages taken into the stream.
    pub trajectories: u64,
    /// ROS 2 `follow_joint_trajectory` goals accepted.
    pub goals: u64,
    /// States published on `state`.
    pub states: u64,
    /// Timed `play` commands: the start cycle's measured start minus the
    /// agreed instant, s.
    pub start_offsets: Vec<f64>,
}

impl Served {
    /// The node's own counts as JSON: `targets`, `chunks`, `malformed`,
    /// `commands`, `trajectories`, `goals`, `states`, `start_offsets_s`
    /// (what `report` and `serve --json` show).
    pub fn counts(&self) -> serde_json::Value {
        serde_json::json!({
            "targets": self.targets,
            "chunks": self.chunks,
            "malformed": self.malformed,
            "commands": self.commands,
            "trajectories": self.trajectories,
            "goals": self.goals,
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
    trajectories: AtomicU64,
    goals: AtomicU64,
}

/// The commanded state of the latest whole cycle, for inputs that start
/// from where the joints are heading (ROS 2 trajectories).
#[derive(Debug, Default, Clone)]
struct Latest {
    /// When the cycle's sample was taken in.
    at: Option<Instant>,
    /// Per joint, the commanded position, rad.
    position: Vec<f64>,
    /// Per joint, the commanded velocity (from the last two cycles), rad/s.
    velocity: Vec<f64>,
}

impl Latest {
    /// Joint `j`'s commanded position `now`, carried on at its velocity
    /// from the cycle seen (for at most 0.1 s); `None` before any cycle.
    fn position_at(&self, j: usize, now: Instant) -> Option<f64> {
        let at = self.at?;
        let age = now.saturating_duration_since(at).as_secs_f64().min(0.1);
        let p = *self.position.get(j)?;
        Some(p + self.velocity.get(j).copied().unwrap_or(0.0) * age)
    }
}

/// What the callbacks and the telemetry loop share.
struct Shared {
    /// The node's stream clock starts here: targets without a stamp, and
    /// ROS 2 messages, are stamped with the seconds since.
    started: Instant,
    /// Counts every input that set the robot moving (a target, a chunk, a
    /// trajectory, a command): a goal that sees it change has been taken
    /// over.
    generation: AtomicU64,
    /// The latest whole cycle's commanded state.
    latest: Mutex<Latest>,
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

impl Default for Shared {
    fn default() -> Self {
        Shared {
            started: Instant::now(),
            generation: AtomicU64::new(0),
            latest: Mutex::new(Latest::default()),
            start: Mutex::new(None),
            timed: Mutex::new(Vec::new()),
            report: Mutex::new(String::new()),
            counts: Counts::default(),
            motion: Mutex::new(Motion::default()),
        }
    }
}

impl Shared {
    /// The node's stream clock now: seconds since [`Shared::started`].
    fn stream_now(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }
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
    let shared = Arc::new(Shared::default());
    *lock(&shared.report) = serde_json::json!({"running": true}).to_string();
    let keys = Keys::declare(session, robot, &runner, planner, config, &shared)?;
    let mut out = Outbound::new(&keys, robot, config, &shared);
    for m in runner.telemetry().iter() {
        match m {
            Telemetry::Cycle(c) => out.cycle(&c)?,
            Telemetry::Fault(f) => {
                eprintln!("fault: {f}");
                out.watch.faults.push(f.to_string());
            }
            Telemetry::Rejected(why) => eprintln!("refused: {why}"),
            Telemetry::Finished(_) => break,
            _ => {}
        }
    }
    if let Some(ros) = &keys.ros {
        // Goals still running end with the run, their results answered.
        ros.finish("the run ended");
    }
    let report = runner.join()?;
    let c = &shared.counts;
    let served = Served {
        targets: c.targets.load(Ordering::Relaxed),
        chunks: c.chunks.load(Ordering::Relaxed),
        malformed: c.malformed.load(Ordering::Relaxed),
        commands: c.commands.load(Ordering::Relaxed),
        trajectories: c.trajectories.load(Ordering::Relaxed),
        goals: c.goals.load(Ordering::Relaxed),
        states: out.states,
        start_offsets: out.offsets,
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

/// The loop's telemetry on its way out: whole cycles to `state` (and to
/// ROS 2), progress to `report`, and the timed starts measured.
struct Outbound<'a> {
    keys: &'a Keys,
    shared: &'a Shared,
    units: Units,
    /// A state is published every this many cycles.
    every: u64,
    watch: Watch,
    /// States published on `state`.
    states: u64,
    /// The last JointState's sequence number.
    ros_seq: i64,
    /// The timed starts measured, s (see [`Served::start_offsets`]).
    offsets: Vec<f64>,
    /// The control period, s.
    period: f64,
}

impl<'a> Outbound<'a> {
    /// Nothing sent yet, on `keys`, at `config`'s state rate.
    fn new(keys: &'a Keys, robot: &RobotInfo, config: &NodeConfig, shared: &'a Shared) -> Self {
        Outbound {
            keys,
            shared,
            units: robot.units,
            every: ((robot.rate_hz / config.state_hz.max(0.1)).round() as u64).max(1),
            watch: Watch::new(robot),
            states: 0,
            ros_seq: 0,
            offsets: Vec::new(),
            period: 1.0 / robot.rate_hz,
        }
    }

    /// Takes one sample of the loop; publishes the cycle it completes when
    /// one is due.
    fn cycle(&mut self, c: &CycleSample) -> Result<(), NodeError> {
        if c.bus == 0 {
            self.note_start(c);
        }
        if let Some(done) = self.watch.cycle(c) {
            self.note_commanded(&done);
            if let Some(ros) = &self.keys.ros {
                ros.cycle(&done, self.units);
            }
            if done.cycle % self.every == 0 {
                self.publish(&done)?;
            }
        }
        Ok(())
    }

    /// Keeps the commanded state of the whole cycle `done` (rad, rad/s)
    /// for the inputs that start from it.
    fn note_commanded(&self, done: &Done) {
        let mut latest = lock(&self.shared.latest);
        let position: Vec<f64> = done
            .commanded()
            .iter()
            .map(|&a| self.units.to_rad(a))
            .collect();
        let velocity = if latest.position.len() == position.len() {
            position
                .iter()
                .zip(&latest.position)
                .map(|(now, before)| (now - before) / self.period)
                .collect()
        } else {
            vec![0.0; position.len()]
        };
        *latest = Latest {
            at: Some(Instant::now()),
            position,
            velocity,
        };
    }

    /// Estimates cycle 0's deadline on the wall clock from bus 0's sample
    /// `c`, then measures the timed starts due by its cycle.
    fn note_start(&mut self, c: &CycleSample) {
        // The earliest estimate wins (a sample arrives after its cycle).
        let now = SystemTime::now();
        let here = now
            .checked_sub(Duration::from_secs_f64(c.time_s.max(0.0)))
            .unwrap_or(now);
        let mut start = lock(&self.shared.start);
        let s = match *start {
            Some(s) if s <= here => s,
            _ => here,
        };
        *start = Some(s);
        drop(start);
        measure_starts(
            self.shared,
            c.cycle,
            s,
            c.time_s + c.lateness.as_secs_f64(),
            &mut self.offsets,
        );
    }

    /// Publishes the whole cycle `done` on `state` (and ROS 2), and as
    /// `report`'s progress.
    fn publish(&mut self, done: &Done) -> Result<(), NodeError> {
        publish_state(&self.keys.state, done)?;
        self.states += 1;
        if let Some(ros) = &self.keys.ros {
            self.ros_seq += 1;
            ros.publish(done, self.units, self.ros_seq)?;
        }
        let progress = serde_json::json!({
            "running": true, "cycle": done.cycle, "t": done.t,
        });
        *lock(&self.shared.report) = progress.to_string();
        Ok(())
    }
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
