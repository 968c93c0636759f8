//! `servobus._native.Robot`: a robot file's robot, its plans and runs. The
//! Python class `servobus.Robot` wraps it (typed reports, numpy arrays).

use std::time::Duration;

use crossbeam_channel::RecvTimeoutError;
use pyo3::prelude::*;
use servobus_protocol::BROADCAST_ID;
use servobus_robot::ports::{bus_ports, open_bus, Allowance};
use servobus_robot::summary::PlanSummary;
use servobus_robot::{Motion, Target, Telemetry};

use crate::calibration::{calibrate_robot, to_json, Calibrated, Where};
use crate::errors::{Class, Failure, Outcome};
use crate::load::load_robot;
use crate::stream::{LiveOptions, Stream};

/// How often a run's telemetry loop looks for Ctrl-C and calls back.
const POLL: Duration = Duration::from_millis(50);

/// A robot: `Robot(robot, port=None, calibration=None)`.
#[pyclass(module = "servobus._native", name = "Robot")]
pub struct Robot {
    robot: servobus_robot::Robot,
    /// The robot as Python gave it (a file, a built-in name or YAML text).
    source: String,
    port: Option<String>,
}

/// What a run recorded, sample by sample: the time (s) and, per joint in
/// the robot's order, the commanded, planned and measured angles (NaN when
/// a joint had no reading yet).
#[derive(Default)]
struct Samples {
    time: Vec<f64>,
    commanded: Vec<Vec<f64>>,
    planned: Vec<Vec<f64>>,
    measured: Vec<Vec<f64>>,
}

impl Samples {
    fn new(joints: usize) -> Self {
        Samples {
            time: Vec::new(),
            commanded: vec![Vec::new(); joints],
            planned: vec![Vec::new(); joints],
            measured: vec![Vec::new(); joints],
        }
    }

    /// Records a cycle sample of the first bus as a new row; other buses'
    /// samples fill the row of the same cycle.
    fn add(&mut self, c: &servobus_robot::CycleSample) {
        if c.bus == 0 && c.joints().first().is_none_or(|j| j.joint == 0) {
            self.time.push(c.time_s);
            for column in self
                .commanded
                .iter_mut()
                .chain(&mut self.planned)
                .chain(&mut self.measured)
            {
                column.push(f64::NAN);
            }
        }
        let Some(row) = self.time.len().checked_sub(1) else {
            return;
        };
        for j in c.joints() {
            let set = |columns: &mut [Vec<f64>], v: f64| {
                if let Some(cell) = columns.get_mut(j.joint).and_then(|c| c.get_mut(row)) {
                    *cell = v;
                }
            };
            set(&mut self.commanded, j.commanded);
            set(&mut self.planned, j.planned);
            set(&mut self.measured, j.measured.unwrap_or(f64::NAN));
        }
    }
}

/// A joint's limits as Python gets them: name, servo ID (a number: a u8
/// would become bytes in a list), min, max, velocity, acceleration, jerk.
type JointLimits = (String, u16, f64, f64, f64, f64, Option<f64>);

/// A run's report (JSON text), its samples, and the exception that stopped
/// it early (Ctrl-C's `KeyboardInterrupt`, or one `on_progress` raised).
type Played = (
    String,
    Vec<f64>,
    Vec<Vec<f64>>,
    Vec<Vec<f64>>,
    Vec<Vec<f64>>,
    Option<PyObject>,
);

impl Robot {
    /// The motion `motion`: a motion file or a built-in name.
    fn motion(&self, motion: &str) -> Outcome<Motion> {
        Ok(self.robot.motion(motion)?)
    }

    /// Where the robot's buses are: its port, or the simulator.
    fn target(&self, virtual_time: bool) -> Target {
        match &self.port {
            Some(p) => Target::Ports(vec![p.clone()]),
            None if virtual_time => Target::VirtualSimulator,
            None => Target::Simulator,
        }
    }
}

/// Calls `on_progress(t, duration)` with the GIL; an exception it raises
/// stops the run like Ctrl-C.
fn progress(py: Python<'_>, callback: &PyObject, t: f64, duration: f64) -> PyResult<()> {
    callback.call1(py, (t, duration))?;
    Ok(())
}

#[pymethods]
impl Robot {
    /// Opens `robot` (a robot file, a built-in name such as `"so101"`, or
    /// YAML text) with `calibration` instead of the calibration file it
    /// names; `port` is its first bus's serial port (None: the built-in
    /// simulator).
    #[new]
    #[pyo3(signature = (robot, port=None, calibration=None))]
    fn new(
        py: Python<'_>,
        robot: &str,
        port: Option<String>,
        calibration: Option<&str>,
    ) -> PyResult<Self> {
        let loaded = py.allow_threads(|| load_robot(robot, calibration))?;
        Ok(Robot {
            robot: loaded,
            source: robot.to_owned(),
            port,
        })
    }

    /// The robot's name.
    #[getter]
    fn name(&self) -> &str {
        self.robot.name()
    }

    /// Its joints' names, in the robot file's order.
    #[getter]
    fn joints(&self) -> Vec<String> {
        self.robot
            .config()
            .joints()
            .map(|j| j.name.clone())
            .collect()
    }

    /// Every joint's limits in the robot's units (its calibration applied):
    /// `(name, servo ID, min, max, max_velocity, max_acceleration,
    /// max_jerk or None)`, in the robot file's order.
    #[getter]
    fn limits(&self) -> Vec<JointLimits> {
        self.robot
            .config()
            .joints()
            .map(|j| {
                (
                    j.name.clone(),
                    u16::from(j.id),
                    j.min,
                    j.max,
                    j.max_velocity,
                    j.max_acceleration,
                    j.max_jerk,
                )
            })
            .collect()
    }

    /// Its default control rate, Hz.
    #[getter]
    fn rate_hz(&self) -> f64 {
        self.robot.config().rate_hz
    }

    /// The unit of its angles: `"deg"` or `"rad"`.
    #[getter]
    fn units(&self) -> &'static str {
        self.robot.config().units.name()
    }

    /// Its port (None: the built-in simulator).
    #[getter]
    fn port(&self) -> Option<&str> {
        self.port.as_deref()
    }

    /// Plans `motion` (a motion file or a built-in name): its
    /// [`PlanSummary`] as JSON text, in the robot's units.
    fn plan(&self, py: Python<'_>, motion: &str) -> PyResult<String> {
        let json = py.allow_threads(|| -> Outcome<String> {
            let motion = self.motion(motion)?;
            let plan = self.robot.plan(&motion)?;
            let config = self.robot.config();
            let summary = PlanSummary::new(&motion, config, &plan, config.units);
            serde_json::to_string(&summary)
                .map_err(|e| Failure::new(Class::Error, format!("the plan's summary as JSON: {e}")))
        })?;
        Ok(json)
    }

    /// Plays `motion` and returns `(report JSON, time, commanded, planned,
    /// measured, exception or None)`. On the simulator in virtual time
    /// unless `real_time`. `on_progress(t, duration)` is called about 20
    /// times a second; Ctrl-C (or an exception in `on_progress`) stops the
    /// run with a jerk-limited stop, and the exception is returned with the
    /// report, for the caller to raise.
    #[pyo3(signature = (motion, on_progress=None, real_time=false))]
    fn play(
        &self,
        py: Python<'_>,
        motion: &str,
        on_progress: Option<PyObject>,
        real_time: bool,
    ) -> PyResult<Played> {
        let motion = py.allow_threads(|| self.motion(motion))?;
        let target = self.target(!real_time);
        let (run, duration) = py.allow_threads(|| -> Outcome<_> {
            let plan = self.robot.plan(&motion)?;
            let duration = plan.duration();
            let connection = self.robot.connect(target)?;
            let mut options = connection.options();
            options.units = Some(self.robot.config().units);
            options.rate_hz = Some(motion.rate_hz(self.robot.config()));
            Ok((connection.play(plan, options)?, duration))
        })?;
        let telemetry = run.telemetry();
        let mut samples = Samples::new(self.robot.config().joints().count());
        let mut interrupted: Option<PyErr> = None;
        let mut last_t = 0.0;
        loop {
            let message = py.allow_threads(|| telemetry.recv_timeout(POLL));
            match message {
                Ok(Telemetry::Cycle(c)) => {
                    last_t = c.time_s;
                    samples.add(&c);
                    // Drain what is there without waking Python for each.
                    while let Ok(Telemetry::Cycle(c)) = telemetry.try_recv() {
                        last_t = c.time_s;
                        samples.add(&c);
                    }
                }
                Ok(Telemetry::Finished(_)) | Err(RecvTimeoutError::Disconnected) => break,
                Ok(_) | Err(RecvTimeoutError::Timeout) => {}
            }
            if interrupted.is_none() {
                let checked = py.check_signals().and_then(|()| match &on_progress {
                    Some(cb) => progress(py, cb, last_t, duration),
                    None => Ok(()),
                });
                if let Err(e) = checked {
                    // A jerk-limited stop; the run ends after it.
                    let _ = run.stop();
                    interrupted = Some(e);
                }
            }
        }
        let report = py.allow_threads(|| run.join().map_err(Failure::from))?;
        let json = serde_json::to_string(&report).map_err(|e| {
            Failure::new(Class::Error, format!("the report does not serialise: {e}"))
        })?;
        Ok((
            json,
            samples.time,
            samples.commanded,
            samples.planned,
            samples.measured,
            interrupted.map(|e| e.into_value(py).into_any()),
        ))
    }

    /// Starts the live loop (as `servobus stream`): the joints hold where
    /// they are and follow the targets sent to the returned stream. `rate`
    /// in Hz (default the robot's); after `timeout` s without a target the
    /// joints stop and hold. Without `tracking_faults` a joint far from its
    /// target (a following error) or held back (a stall: a gripper closed
    /// on an object) does not end the run.
    #[pyo3(signature = (rate=None, timeout=0.25, tracking_faults=true))]
    fn stream(
        &self,
        py: Python<'_>,
        rate: Option<f64>,
        timeout: f64,
        tracking_faults: bool,
    ) -> PyResult<Stream> {
        let target = self.target(false);
        let live = LiveOptions {
            rate,
            timeout,
            tracking_faults,
        };
        Ok(py.allow_threads(|| Stream::start(&self.robot, target, &live))?)
    }

    /// Runs the calibration procedure of `servobus calibrate` on the robot
    /// as designed, unattended (each step ends once the joints have moved
    /// and been held still), and returns the calibration as JSON text. On
    /// the built-in simulator (no port) in virtual time, `hand` (a hand file
    /// or a built-in name) moving the joints and the servos mounted as
    /// `mounting` says; `timeout` (s) bounds each step. `on_step(name)` is
    /// called as each step begins (`torque_off`, `hold_pose`, `sweep`,
    /// `done`); Ctrl-C, or an exception `on_step` raises, ends the
    /// procedure at once and is raised.
    #[pyo3(signature = (hand=None, mounting=None, timeout=600.0, on_step=None))]
    fn calibrate(
        &self,
        py: Python<'_>,
        hand: Option<&str>,
        mounting: Option<&str>,
        timeout: f64,
        on_step: Option<PyObject>,
    ) -> PyResult<String> {
        let at = Where {
            port: self.port.as_deref(),
            hand,
            mounting,
            timeout,
            on_step,
        };
        match py.allow_threads(|| calibrate_robot(&self.source, at)) {
            Calibrated::Taken(taken) => Ok(to_json(&taken?)?),
            Calibrated::Stopped(e) => Err(e),
        }
    }

    /// Checks every bus with the doctor: on the robot's port (the first
    /// bus; the robot file's ports past it) or on the built-in simulator.
    /// With `fix`, applies the fixes that are writes and checks again
    /// (homing offsets stored in EEPROM only with `write_servos`). JSON
    /// text: `status`, `buses` (findings, fixes), `unchecked`.
    #[pyo3(signature = (fix=false, write_servos=false))]
    fn doctor(&self, py: Python<'_>, fix: bool, write_servos: bool) -> PyResult<String> {
        let port = self.port.as_deref();
        Ok(py.allow_threads(|| crate::doctor::doctor(&self.robot, port, fix, write_servos))?)
    }

    /// Turns the torque off on every servo of every bus of the robot (one
    /// broadcast WRITE a bus, so a servo that answers nothing is reached
    /// too). Nothing to do on the built-in simulator: it holds no torque
    /// outside a run.
    fn torque_off(&self, py: Python<'_>) -> PyResult<()> {
        let Some(port) = self.port.as_deref() else {
            return Ok(());
        };
        py.allow_threads(|| -> Outcome<()> {
            let config = self.robot.config();
            for (bus, port) in config.buses.iter().zip(bus_ports(config, &[port])) {
                let Some(port) = port else {
                    return Err(Failure::new(
                        Class::PortError,
                        format!(
                            "bus `{}` has no port: give it a `port:` in the robot file",
                            bus.name
                        ),
                    ));
                };
                let mut serial = open_bus(bus, &port, Allowance::Assumed)?;
                let torque = serial
                    .settings()
                    .series
                    .map()
                    .get("torque_enable")
                    .ok_or_else(|| {
                        Failure::new(Class::Error, "the servos have no torque_enable register")
                    })?;
                serial.write(BROADCAST_ID, torque.address, &[0])?;
            }
            Ok(())
        })?;
        Ok(())
    }

    fn __repr__(&self) -> String {
        let on = self.port.as_deref().unwrap_or("the simulator");
        format!("<servobus.Robot {} on {on}>", self.robot.name())
    }
}
