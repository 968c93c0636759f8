//! `servobus follow`: a leader arm, moved by hand with its torque off,
//! drives a follower arm. Every follower period the leader's positions are
//! read through its own calibration, matched to the follower's joints by
//! name and sent to the follower's loop as live targets (a jerk-limited
//! step toward the newest each cycle). The leader is never written to.
//!
//! Without ports both arms are simulated, the leader moved by a scripted
//! hand (`--leader-hand`), so the whole command runs without hardware. A
//! live line shows the rates, the latency and the error; the report gives
//! the latency from a leader reading to the follower's goals on the wire
//! (p50, p99) and the follower's error against the leader, each reading
//! of the follower against the leader's pose at that reading's time
//! ([`against`]).
//!
//! A follower joint pressed against a stop (a gripper closed on its end
//! stop or on an object) does not end the session: the runtime holds it
//! with bounded effort and says so (`Telemetry::Stall`), and follow prints a
//! warning line and counts it in the report (`stalls`, `stalled_s` per
//! joint). When the session ends on an error (the leader lost, the
//! follower's port lost, a fault), `--log`, `--record` and `--plot` are
//! still written whole with what was captured and the report is printed;
//! the exit code is 1.

mod against;
mod args;
mod report;
mod seen;

use std::io::{IsTerminal, Write};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use against::{Figures, LeaderTrail, ERRORS_FROM};
pub use args::{Args, FollowLimits};
use report::finish;
use seen::Seen;

use crossbeam_channel::Receiver;

use servobus_config::{load_robot, JointMap, Robot, RobotOptions, Units};
use servobus_robot::bus::{Bus, Clock, Transport};
use servobus_robot::sim::{Hand, SimRobot};
use servobus_robot::teach::read_angle;
use servobus_robot::{live_options, Command, LiveTarget, Run, RunOptions, TargetSender, Telemetry};

use crate::shared::out::errln;
use crate::shared::ports::{every_port, Allowance, Ports};

/// How long a leader joint's readings may fail (late or garbled replies)
/// before the leader counts as lost.
const LEADER_PATIENCE: Duration = Duration::from_millis(500);

/// The highest rate the leader is read at, Hz.
const LEADER_HZ: f64 = 50.0;

/// One leader joint that drives a follower joint.
struct LeaderJoint {
    name: String,
    bus: usize,
    id: u8,
    map: JointMap,
    /// The follower's joint index.
    to: usize,
    /// When its readings began to fail, while they do.
    missing_since: Option<Instant>,
}

/// The leader arm: read only.
struct Leader<T: Transport> {
    buses: Vec<Bus<T>>,
    joints: Vec<LeaderJoint>,
    /// Readings skipped for a late or garbled reply.
    missed: u64,
}

impl<T: Transport> Leader<T> {
    fn new(leader: &Robot, follower: &Robot, buses: Vec<Bus<T>>) -> anyhow::Result<Self> {
        let mut joints = Vec::new();
        for (b, bus) in leader.buses.iter().enumerate() {
            for j in &bus.joints {
                if let Some(to) = follower.joints().position(|f| f.name == j.name) {
                    joints.push(LeaderJoint {
                        name: j.name.clone(),
                        bus: b,
                        id: j.id,
                        map: JointMap::new(j, leader.units),
                        to,
                        missing_since: None,
                    });
                }
            }
        }
        if joints.is_empty() {
            return Err(crate::shared::exit::input(format!(
                "the leader {} and the follower {} have no joint name in common",
                leader.name, follower.name
            )));
        }
        Ok(Leader {
            buses,
            joints,
            missed: 0,
        })
    }

    /// Every matched joint's angle now (rad), in `out` by follower index
    /// (`None` for a reading missed), and into `trail` with the time its
    /// servo took it (s on the bus's clock, the process's one).
    ///
    /// A reading lost to a late or garbled reply (a loaded machine, a
    /// noisy cable) is skipped and counted: the follower keeps to the
    /// last target of that joint. Only a joint whose readings have failed
    /// for [`LEADER_PATIENCE`], or a port that fails, loses the leader.
    fn read(
        &mut self,
        out: &mut [Option<f64>],
        trail: &mut LeaderTrail,
        now: Instant,
    ) -> anyhow::Result<()> {
        for j in &mut self.joints {
            let bus = &mut self.buses[j.bus];
            let read = read_angle(bus, j.id, &j.map);
            match read {
                Ok(angle) => {
                    j.missing_since = None;
                    out[j.to] = Some(angle);
                    trail.push(j.to, bus.heard().as_secs_f64(), angle);
                }
                Err(e)
                    if e.is_retryable()
                        && now.duration_since(*j.missing_since.get_or_insert(now))
                            < LEADER_PATIENCE =>
                {
                    self.missed += 1;
                    out[j.to] = None;
                }
                Err(e) => {
                    let what = match j.missing_since {
                        Some(since) if e.is_retryable() => format!(
                            "reading the leader's {} (ID {}), silent for {:.1} s",
                            j.name,
                            j.id,
                            now.duration_since(since).as_secs_f64()
                        ),
                        _ => format!("reading the leader's {} (ID {})", j.name, j.id),
                    };
                    return Err(anyhow::Error::new(e).context(what));
                }
            }
        }
        Ok(())
    }
}

/// Runs `servobus follow`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    if let Some(path) = &args.plot {
        crate::shared::flags::check_plot_format(path, &["svg", "png"])?;
    }
    for (flag, path) in [
        ("--log", &args.log),
        ("--plot", &args.plot),
        ("--record", &args.record),
    ] {
        if let Some(path) = path {
            crate::shared::flags::check_writable(flag, path)?;
        }
    }
    args.rerun.check()?;
    let robot = load_robot(
        &args.robot.path,
        &RobotOptions::default().calibration(args.robot.hardware.calibration.as_deref()),
    )?;
    let robot = match args.limits {
        FollowLimits::Model => robot.with_model_limits(),
        FollowLimits::Robot => robot,
    };
    let leader_path = args.leader_robot.as_ref().unwrap_or(&args.robot.path);
    let leader_robot = load_robot(
        leader_path,
        &RobotOptions::default().calibration(args.leader_calibration.as_deref()),
    )?;
    let options = live_options(&robot);
    match &args.leader {
        Some(port) => {
            let ports = match every_port(&leader_robot, &[port]) {
                Ports::Every(ports) => ports,
                _ => {
                    return Err(crate::shared::exit::input(
                        "--leader sets the leader's first bus; give the others a `port:` in its robot file",
                    ))
                }
            };
            let mut buses =
                crate::shared::ports::open_buses(&leader_robot, &ports, Allowance::Assumed, None)?;
            // Angles go through the leader's calibration: its servos must
            // match it.
            crate::shared::check_buses(&leader_robot, &mut buses, &ports)?;
            let leader = Leader::new(&leader_robot, &robot, buses)?;
            drive(&args, &robot, leader, options)
        }
        None => {
            let clock = crate::shared::ports::system_clock();
            let mut sim = SimRobot::builder(&leader_robot);
            if let Some(path) = &args.leader_hand {
                sim = sim.hand(Hand::load(path, &leader_robot)?);
            }
            let buses = sim.build()?.wall_buses(&clock);
            let leader = Leader::new(&leader_robot, &robot, buses)?;
            drive(&args, &robot, leader, options)
        }
    }
}

/// Follows `leader` with the follower `robot` until Ctrl-C, `--seconds`,
/// or the follower's run ends.
fn drive<T: Transport>(
    args: &Args,
    robot: &Robot,
    mut leader: Leader<T>,
    options: RunOptions,
) -> anyhow::Result<ExitCode> {
    let names: Vec<String> = robot.joints().map(|j| j.name.clone()).collect();
    // The leader is read at the follower's rate up to LEADER_HZ: faster
    // readings add mostly their tick noise to the targets' speed and
    // acceleration estimates (measured on the simulator: 100 Hz follows
    // worse than 50 Hz).
    let rate = options.rate_hz.unwrap_or(robot.rate_hz).min(LEADER_HZ);
    let terminal = std::io::stderr().is_terminal();
    let mut seen = Seen::new(args, robot, &names, terminal)?;
    let started = crate::shared::ports::start_live(
        robot,
        args.robot.hardware.port.as_deref(),
        options,
        args.store.write_servos,
    );
    let (runner, rerun) = std::mem::take(&mut seen.rerun).unless_refused(started)?;
    seen.rerun = rerun;
    crate::shared::install_ctrl_c(runner.commands());
    let mut session = Session::new(args, &names, robot.units, &runner, rate, terminal);
    // Counted from ERRORS_FROM on, on the clock both arms' readings are
    // stamped on.
    let from = crate::shared::ports::system_clock().now().as_secs_f64() + ERRORS_FROM;
    seen.errors.count_from(from);
    // Why the session ended early on the leader's side, if it did.
    let lost = session.follow(&runner, &mut leader, &mut seen);
    if seen.live_line {
        errln!();
    }
    if leader.missed > 0 {
        errln!(
            "warning: {} leader readings were skipped (a late or garbled reply); \
             the follower kept to each joint's last target meanwhile",
            leader.missed
        );
    }
    // The follower stops (jerk limited) and the run ends.
    let _ = runner.commands().send(Command::Stop);
    for m in session.telemetry.iter() {
        if matches!(m, Telemetry::Finished(_)) {
            break;
        }
        seen.take(m, args.record.is_some());
    }
    let report = runner.join()?;
    let code = finish(args, robot, &report, seen, lost.as_deref())?;
    match lost {
        // Said last, once everything is written: exit 1.
        Some(why) => Err(anyhow::anyhow!(why)),
        None => Ok(code),
    }
}

/// The leader's side of a session: its readings sent to the follower as
/// live targets every leader period, the follower's telemetry taken in,
/// and the live line.
struct Session<'a> {
    args: &'a Args,
    /// The follower's joint names.
    names: &'a [String],
    units: Units,
    targets: TargetSender,
    telemetry: Receiver<Telemetry>,
    /// The leader's readings, with the times its servos took them.
    trail: LeaderTrail,
    /// The newest reading by follower joint (`None`: missed).
    pose: Vec<Option<f64>>,
    started: Instant,
    /// Between two readings of the leader.
    period: Duration,
    /// Readings of the leader so far.
    reads: u64,
    /// Stderr is a terminal: the live line is rewritten in place.
    terminal: bool,
    /// How often the live line is shown.
    live_every: Duration,
    /// When the live line was last shown.
    shown: Instant,
}

impl<'a> Session<'a> {
    /// A session starting now, reading the leader at `rate` Hz.
    fn new(
        args: &'a Args,
        names: &'a [String],
        units: Units,
        runner: &Run,
        rate: f64,
        terminal: bool,
    ) -> Self {
        let started = Instant::now();
        Session {
            args,
            names,
            units,
            targets: runner.targets(),
            telemetry: runner.telemetry(),
            trail: LeaderTrail::new(names.len()),
            pose: vec![None; names.len()],
            started,
            period: Duration::from_secs_f64(1.0 / rate),
            reads: 0,
            terminal,
            // The live line: every 0.5 s on a terminal, rewritten in
            // place; every 5 s in a log, a line of its own.
            live_every: Duration::from_millis(if terminal { 500 } else { 5000 }),
            shown: started,
        }
    }

    /// Reads the leader and sends its pose each period until the run
    /// ends or `--seconds` have passed; why the leader's side ended the
    /// session, if it did.
    fn follow<T: Transport>(
        &mut self,
        runner: &Run,
        leader: &mut Leader<T>,
        seen: &mut Seen,
    ) -> Option<String> {
        let mut next = self.started;
        loop {
            let now = Instant::now();
            let t = now.duration_since(self.started).as_secs_f64();
            if runner.is_finished() || self.args.seconds.is_some_and(|s| t >= s.as_secs_f64()) {
                return None;
            }
            if let Err(why) = self.step(leader, seen, t) {
                return Some(why);
            }
            if !self.args.json && now.duration_since(self.shown) >= self.live_every {
                self.shown = now;
                self.show(seen, t);
            }
            next += self.period;
            let after = Instant::now();
            if next > after {
                std::thread::sleep(next - after);
            } else {
                next = after;
            }
        }
    }

    /// One reading of the leader, at `t` s, sent as the follower's target,
    /// and the follower's telemetry since taken in; why not, when the
    /// leader is lost.
    fn step<T: Transport>(
        &mut self,
        leader: &mut Leader<T>,
        seen: &mut Seen,
        t: f64,
    ) -> Result<(), String> {
        self.pose.fill(None);
        if let Err(e) = leader.read(&mut self.pose, &mut self.trail, Instant::now()) {
            // The follower stops and everything captured is kept.
            return Err(format!(
                "the leader was lost at {t:.1} s: {}",
                crate::shared::exit::message(&e)
            ));
        }
        let taken = Instant::now();
        self.reads += 1;
        let joints: Vec<(String, f64)> = self
            .names
            .iter()
            .zip(&self.pose)
            .filter_map(|(n, p)| p.map(|p| (n.clone(), p)))
            .collect();
        let stamp = taken.duration_since(self.started).as_secs_f64();
        // A reading whose every joint was missed sends nothing.
        let sent = if joints.is_empty() {
            Ok(())
        } else {
            send(
                &self.targets,
                LiveTarget::named(stamp, joints).taken_at(taken),
            )
        };
        if let Err(e) = sent {
            return Err(format!("at {t:.1} s: {e}"));
        }
        while let Ok(m) = self.telemetry.try_recv() {
            seen.take(m, self.args.record.is_some());
        }
        seen.errors.settle(&self.trail, self.units);
        Ok(())
    }

    /// Shows the live line on stderr, `t` s into the session.
    fn show(&self, seen: &Seen, t: f64) {
        let errors = seen.errors.figures();
        let line = live_line(
            &self.targets,
            t,
            self.reads,
            seen.cycles,
            errors,
            self.units.to_string(),
        );
        let mut err = std::io::stderr().lock();
        let _ = if self.terminal {
            write!(err, "\r{line}   ")
        } else {
            writeln!(err, "{line}")
        };
    }
}

fn send(targets: &TargetSender, target: LiveTarget) -> anyhow::Result<()> {
    match targets.send(target) {
        Ok(_) | Err(servobus_robot::TargetError::Ended) => Ok(()),
        Err(e) => Err(anyhow::anyhow!("the leader's reading was refused: {e}")),
    }
}

/// The live line for stderr: rates, latency so far, worst error.
fn live_line(
    targets: &TargetSender,
    t: f64,
    reads: u64,
    cycles: u64,
    errors: &[Figures],
    units: String,
) -> String {
    let latency = targets.so_far().and_then(|l| l.latency_ms).map_or_else(
        || "-".to_owned(),
        |q| format!("{:.1} ms (p99 {:.1})", q.p50, q.p99),
    );
    let worst = errors.iter().map(|e| e.1).fold(0.0, f64::max);
    format!(
        "{t:6.1} s  leader {:.0} Hz  follower {:.0} Hz  latency {latency}  error max {worst:.2} {units}",
        reads as f64 / t.max(1e-3),
        cycles as f64 / t.max(1e-3),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use servobus_config::MODEL_JERK_RAMP_S;

    #[test]
    fn model_limits_are_the_servos_top_speed_and_fastest_ramp_in_the_robots_units() {
        let robot = load_robot(
            &crate::shared::flags::robot_arg("so101").unwrap_or_default(),
            &RobotOptions::default().calibration(None),
        )
        .expect("the built-in arm loads");
        let before: Vec<(f64, f64)> = robot.joints().map(|j| (j.min, j.max)).collect();
        let fast = robot.clone().with_model_limits();
        for ((j, slow), range) in fast.joints().zip(robot.joints()).zip(&before) {
            let (v, a) = j.model.fastest_profile().expect("STS servos");
            assert!((robot.units.to_rad(j.max_velocity) - v.to_radians()).abs() < 1e-9);
            assert!((robot.units.to_rad(j.max_acceleration) - a.to_radians()).abs() < 1e-9);
            assert_eq!(j.max_jerk, Some(j.max_acceleration / MODEL_JERK_RAMP_S));
            assert!(j.max_velocity > slow.max_velocity, "{}", j.name);
            // The position limits are the robot file's.
            assert_eq!((j.min, j.max), *range, "{}", j.name);
        }
    }
}
