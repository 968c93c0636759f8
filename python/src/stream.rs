//! `servobus._native.Stream`: the live loop of `servobus stream`, fed from
//! Python: targets in, the joints' state out.

use std::sync::{Arc, Mutex};
use std::time::Instant;

use pyo3::prelude::*;
use pyo3::types::PyMapping;
use servobus_config::{BaseTarget, Units};
use servobus_robot::{
    Chunk, Command, LiveTarget, Run, RunOptions, TargetError, TargetSender, Telemetry,
};

use servobus_robot::odometry::Odometer;

use crate::errors::{chain, poisoned, Class, Failure, Outcome};

/// The latest state of every joint, in the robot's units.
#[derive(Debug, Clone, Default)]
struct State {
    time: f64,
    position: Vec<f64>,
    velocity: Vec<f64>,
    error: Vec<f64>,
    commanded: Vec<f64>,
    flags: Vec<u8>,
    faults: Vec<String>,
    /// A mobile base's odometry: x, y (m) and heading (rad).
    base: Option<(f64, f64, f64)>,
}

/// The state of the joints as Python gets it: `(time, position, velocity,
/// error, commanded, status flags, faults so far)`.
type StateTuple = (
    f64,
    Vec<f64>,
    Vec<f64>,
    Vec<f64>,
    Vec<f64>,
    Vec<u16>,
    Vec<String>,
);

/// How a live run is started.
pub(crate) struct LiveOptions {
    /// Control rate, Hz (None: the robot's).
    pub rate: Option<f64>,
    /// Seconds without a target after which the joints stop and hold.
    pub timeout: f64,
    /// Whether a following error or a stall is a fault that ends the run.
    pub tracking_faults: bool,
}

/// A live run of a robot, fed targets from Python.
#[pyclass(module = "servobus._native", name = "Stream")]
pub struct Stream {
    runner: Mutex<Option<Run>>,
    targets: TargetSender,
    units: Units,
    /// The robot, whose base (if any) `send_base` drives.
    config: servobus_config::Robot,
    started: Instant,
    state: Arc<Mutex<State>>,
    watcher: Mutex<Option<std::thread::JoinHandle<()>>>,
}

impl Stream {
    /// Starts the live loop of `robot` at `target` through the facade's
    /// [`servobus_robot::Connection::live`]: the same connection (and
    /// calibration check) as a play, the options of `servobus stream`.
    pub(crate) fn start(
        robot: &servobus_robot::Robot,
        target: servobus_robot::Target,
        live: &LiveOptions,
    ) -> Outcome<Stream> {
        let timeout = crate::checks::timeout("timeout", live.timeout)?;
        let rate = crate::checks::rate(live.rate)?;
        let config = robot.config();
        let connection = robot.connect(target)?;
        let mut options = connection.options();
        options.rate_hz = rate;
        // Live targets start where the joints are: no approach to a path.
        options.approach = None;
        options.settle = RunOptions::default().settle;
        options.target_timeout = timeout;
        options.units = Some(config.units);
        if !live.tracking_faults {
            options.faults.following_error = f64::INFINITY;
            options.faults.stall_error = f64::INFINITY;
        }
        let runner = connection.live(options)?;
        let n = config.joints().count();
        let state = Arc::new(Mutex::new(State {
            position: vec![f64::NAN; n],
            velocity: vec![f64::NAN; n],
            error: vec![f64::NAN; n],
            commanded: vec![f64::NAN; n],
            flags: vec![0; n],
            ..State::default()
        }));
        let telemetry = runner.telemetry();
        let shared = Arc::clone(&state);
        let mut odometer = Odometer::of(config, config.units);
        let watcher = std::thread::Builder::new()
            .name("servobus-py-state".into())
            .spawn(move || {
                for message in telemetry.iter() {
                    let Ok(mut s) = shared.lock() else { return };
                    match message {
                        Telemetry::Cycle(c) => {
                            s.time = c.time_s;
                            if let Some(o) = odometer.as_mut() {
                                let p = o.take(&c);
                                s.base = Some((p.x_m, p.y_m, p.theta_rad));
                            }
                            for j in c.joints() {
                                let k = j.joint;
                                if k < s.position.len() {
                                    s.position[k] = j.measured.unwrap_or(f64::NAN);
                                    s.velocity[k] = j.velocity;
                                    s.error[k] = j.error;
                                    s.commanded[k] = j.commanded;
                                    s.flags[k] = j.flags.0;
                                }
                            }
                        }
                        Telemetry::Fault(f) => s.faults.push(f.to_string()),
                        Telemetry::Finished(_) => return,
                        _ => {}
                    }
                }
            })
            .map_err(|e| Failure::new(Class::Error, format!("cannot start a thread: {e}")))?;
        Ok(Stream {
            targets: runner.targets(),
            runner: Mutex::new(Some(runner)),
            units: config.units,
            config: config.clone(),
            started: Instant::now(),
            state,
            watcher: Mutex::new(Some(watcher)),
        })
    }

    /// Sends `command` to the run, if it still runs.
    fn command(&self, command: Command) -> Outcome<()> {
        let runner = self.runner.lock().map_err(poisoned)?;
        match runner.as_ref() {
            Some(r) if !r.is_finished() => Ok(r.send(command)?),
            _ => Ok(()),
        }
    }

    /// Ends the run with `command` and returns its report as JSON text
    /// (None when it was already taken).
    fn finish(&self, command: Command) -> Outcome<Option<String>> {
        self.command(command)?;
        let runner = self.runner.lock().map_err(poisoned)?.take();
        let Some(runner) = runner else {
            return Ok(None);
        };
        let report = runner.join()?;
        if let Some(w) = self.watcher.lock().map_err(poisoned)?.take() {
            let _ = w.join();
        }
        serde_json::to_string(&report)
            .map(Some)
            .map_err(|e| Failure::new(Class::Error, format!("the report does not serialise: {e}")))
    }
}

#[pymethods]
impl Stream {
    /// Sends a target: `joints` maps joint names to angles in the robot's
    /// units (joints not named keep their targets). Returns how many angles
    /// were beyond the joint limits and clamped. Raises `UsageError` for an
    /// unknown joint or an angle that is not a number, `Error` once the run
    /// has ended.
    fn send(&self, py: Python<'_>, joints: Vec<(String, f64)>) -> PyResult<usize> {
        let units = self.units;
        let stamp = self.started.elapsed().as_secs_f64();
        let joints: Vec<(String, f64)> = joints
            .into_iter()
            .map(|(name, a)| (name, units.to_rad(a)))
            .collect();
        let sent = py.allow_threads(|| self.targets.send(LiveTarget::named(stamp, joints)));
        match sent {
            Ok(clamped) => Ok(clamped),
            Err(TargetError::Ended) => {
                Err(Failure::new(Class::Error, "the stream has ended").into())
            }
            Err(e) => Err(Failure::usage(chain(&e)).into()),
        }
    }

    /// Sends a velocity to the robot's mobile base: `x` and `y` in m/s
    /// (forward, left), `theta` in the robot's units per second
    /// (counter-clockwise): its wheels' speeds, all scaled together within
    /// their limits so that the direction of travel is kept. Returns how
    /// many wheel speeds were clamped (0 once scaled). Raises `UsageError`
    /// for a robot without a base or a velocity it cannot take (a
    /// differential base sideways, a number that is not finite), `Error`
    /// once the run has ended.
    fn send_base(&self, py: Python<'_>, x: f64, y: f64, theta: f64) -> PyResult<usize> {
        let stamp = self.started.elapsed().as_secs_f64();
        let wheels = self
            .config
            .wheel_targets(&BaseTarget { x, y, theta })
            .map_err(|e| Failure::usage(e.to_string()))?;
        let target = LiveTarget::named(stamp, wheels.wheels);
        match py.allow_threads(|| self.targets.send(target)) {
            Ok(clamped) => Ok(clamped),
            Err(TargetError::Ended) => {
                Err(Failure::new(Class::Error, "the stream has ended").into())
            }
            Err(e) => Err(Failure::usage(chain(&e)).into()),
        }
    }

    /// Tells grippers to grasp: `grasps` maps joint names to efforts, each
    /// in percent of its servo's torque (above 0, at most 100). Each joint
    /// named closes until it meets something, then holds there pushing with
    /// that effort; a later target giving it a position releases it. The
    /// other joints keep their targets. Raises `UsageError` for a `grasps`
    /// that is not a mapping of names to numbers, names no joint, an
    /// unknown joint, an effort out of range or a wheel, `Error` once the
    /// run has ended.
    fn send_grasp(&self, py: Python<'_>, grasps: &Bound<'_, PyAny>) -> PyResult<()> {
        let grasps = grasp_efforts(grasps)?;
        let stamp = self.started.elapsed().as_secs_f64();
        let target = LiveTarget::named(stamp, Vec::new()).with_grasps(grasps);
        match py.allow_threads(|| self.targets.send(target)) {
            Ok(_) => Ok(()),
            Err(TargetError::Ended) => {
                Err(Failure::new(Class::Error, "the stream has ended").into())
            }
            Err(e) => Err(Failure::usage(chain(&e)).into()),
        }
    }

    /// Sends an action chunk: `joints` maps joint names to their positions
    /// (robot units), one per point; the points are `dt` s apart from now,
    /// or at `times` s from now (increasing; evenly spaced ones are sent
    /// as `dt`). The loop follows the chunk as a timed path through its
    /// points, within the limits; it replaces what is left of the last
    /// chunk from the commanded state, its points already past skipped.
    /// Returns how many positions were clamped to the limits. Raises
    /// `UsageError` for a bad chunk, `Error` once the run has ended.
    #[pyo3(signature = (joints, dt=None, times=None))]
    fn send_chunk(
        &self,
        py: Python<'_>,
        joints: Vec<(String, Vec<f64>)>,
        dt: Option<f64>,
        times: Option<Vec<f64>>,
    ) -> PyResult<usize> {
        let units = self.units;
        let stamp = self.started.elapsed().as_secs_f64();
        let joints: Vec<(String, Vec<f64>)> = joints
            .into_iter()
            .map(|(name, q)| (name, q.into_iter().map(|a| units.to_rad(a)).collect()))
            .collect();
        let chunk = match (dt, times) {
            (Some(dt), None) => {
                chunk_interval(dt)?;
                Chunk::named(Some(stamp), dt, joints)
            }
            // As dt only when every joint has one position per time: the
            // runtime then still refuses lengths that differ.
            (None, Some(times)) => {
                chunk_times(&times)?;
                match even_spacing(&times)
                    .filter(|_| joints.iter().all(|(_, q)| q.len() == times.len()))
                {
                    Some((first, dt)) => Chunk::named(Some(stamp + first), dt, joints),
                    None => Chunk::timed(times.into_iter().map(|t| stamp + t).collect(), joints),
                }
            }
            _ => {
                return Err(
                    Failure::usage("send_chunk: give either dt (s) or times (s from now)").into(),
                )
            }
        };
        let sent = py.allow_threads(|| self.targets.send_chunk(chunk));
        match sent {
            Ok(clamped) => Ok(clamped),
            Err(TargetError::Ended) => {
                Err(Failure::new(Class::Error, "the stream has ended").into())
            }
            Err(e) => Err(Failure::usage(chain(&e)).into()),
        }
    }

    /// The joints' latest state: `(time, position, velocity, error,
    /// commanded, status flags, faults)`, lists in the robot's joint order.
    fn state(&self) -> PyResult<StateTuple> {
        let s = self.state.lock().map_err(poisoned)?.clone();
        // Numbers for Python: a list of u8 would become bytes.
        let flags = s.flags.into_iter().map(u16::from).collect();
        Ok((
            s.time,
            s.position,
            s.velocity,
            s.error,
            s.commanded,
            flags,
            s.faults,
        ))
    }

    /// A mobile base's odometry so far, from its wheels' measured speeds:
    /// `(x, y, theta)`, metres forward and to the left of where it started
    /// and its heading in the robot's units, counter-clockwise; `None` for
    /// a robot without a base.
    fn base_pose(&self) -> PyResult<Option<(f64, f64, f64)>> {
        let s = self.state.lock().map_err(poisoned)?;
        let units = self.units;
        Ok(s.base.map(|(x, y, theta)| (x, y, units.from_rad(theta))))
    }

    /// Whether the run has ended (a stop, torque off or a fault).
    #[getter]
    fn finished(&self) -> PyResult<bool> {
        let runner = self.runner.lock().map_err(poisoned)?;
        Ok(runner.as_ref().is_none_or(Run::is_finished))
    }

    /// Stops the joints (jerk limited), ends the run and returns its report
    /// as JSON text (None when it was already returned).
    fn stop(&self, py: Python<'_>) -> PyResult<Option<String>> {
        Ok(py.allow_threads(|| self.finish(Command::Stop))?)
    }

    /// Turns the torque off on every servo, ends the run and returns its
    /// report as JSON text (None when it was already returned).
    fn torque_off(&self, py: Python<'_>) -> PyResult<Option<String>> {
        Ok(py.allow_threads(|| self.finish(Command::TorqueOff))?)
    }
}

/// The `(joint, effort %)` pairs of `send_grasp`'s mapping, in its order;
/// at least one. Whether each is a grasp the joint can make is the run's
/// to check, as for every sender.
fn grasp_efforts(grasps: &Bound<'_, PyAny>) -> PyResult<Vec<(String, f64)>> {
    const SHAPE: &str = "give a dict of joint name to effort (percent of the servo's torque), \
                         e.g. {\"gripper\": 40}";
    let map = grasps.downcast::<PyMapping>().map_err(|_| {
        let kind = grasps
            .get_type()
            .name()
            .map_or_else(|_| "?".to_string(), |n| n.to_string());
        Failure::usage(format!("send_grasp: got a `{kind}`: {SHAPE}"))
    })?;
    let mut out = Vec::new();
    for item in map.items()?.iter() {
        let (name, effort): (Bound<'_, PyAny>, Bound<'_, PyAny>) = item.extract()?;
        let name: String = name.extract().map_err(|_| {
            Failure::usage(format!("send_grasp: a joint name is not text: {SHAPE}"))
        })?;
        let effort: f64 = effort.extract().map_err(|_| {
            Failure::usage(format!(
                "send_grasp: joint `{name}`: the effort is not a number (percent of the servo's torque)"
            ))
        })?;
        out.push((name, effort));
    }
    if out.is_empty() {
        return Err(Failure::usage(format!("send_grasp: no joint named: {SHAPE}")).into());
    }
    Ok(out)
}

/// Checks a chunk's interval: finite, positive, at most an hour.
fn chunk_interval(dt: f64) -> Outcome<()> {
    crate::checks::timeout("the chunk's dt", dt).map(drop)
}

/// Checks a chunk's times (s from now): each a number within an hour of
/// now, as a timeout is ([`crate::checks::MAX_TIMEOUT_S`]); a point due
/// 1e300 s from now is no point of a chunk. Whether they increase is the
/// loop's check, as for every sender.
fn chunk_times(times: &[f64]) -> Outcome<()> {
    use crate::checks::MAX_TIMEOUT_S;
    match times
        .iter()
        .find(|t| !(-MAX_TIMEOUT_S..=MAX_TIMEOUT_S).contains(*t))
    {
        None => Ok(()),
        Some(&t) => Err(Failure::usage(format!(
            "the chunk's time {} s is outside -{MAX_TIMEOUT_S} to {MAX_TIMEOUT_S} s from now \
             (an hour either way)",
            servobus_config::limits::Rounded(t)
        ))
        .with("value", crate::errors::Field::Float(t))),
    }
}

/// `(first, dt)` when `times` are evenly spaced (to a microsecond), at
/// least two of them, increasing.
fn even_spacing(times: &[f64]) -> Option<(f64, f64)> {
    let (&first, &last) = (times.first()?, times.last()?);
    if times.len() < 2 || !(first.is_finite() && last.is_finite()) {
        return None;
    }
    let dt = (last - first) / (times.len() - 1) as f64;
    let even = times
        .iter()
        .enumerate()
        .all(|(k, t)| (t - (first + k as f64 * dt)).abs() <= 1e-6);
    (even && dt > 0.0 && chunk_interval(dt).is_ok()).then_some((first, dt))
}

impl Drop for Stream {
    fn drop(&mut self) {
        let _ = self.finish(Command::Stop);
    }
}
