//! Calibrations from Python: the procedure of `servobus calibrate` on a
//! robot's servos (or on the simulator, a scripted hand moving the joints),
//! LeRobot calibration files in and out, loading and saving. Python gets a
//! calibration as JSON text (the calibration file's fields, each joint with
//! its servo's `deg_per_tick` besides); `servobus.Calibration` types it.

use std::path::Path;
use std::time::Duration;

use pyo3::prelude::*;
use servobus_config::Calibration;
use servobus_robot::calibrate::{
    calibrate, from_lerobot, to_lerobot, LiveJoint, Operator, ProcedureOptions, Step, PATIENCE,
    PATIENT_RETRIES,
};
use servobus_robot::ports::{every_port, open_buses, Allowance};
use servobus_robot::sim::SimRobot;

use crate::errors::{chain, Class, Failure, Field, Outcome};
use crate::load::load_design;
use crate::sim::with_bodies;

/// The field every joint gets for Python, and loses on the way back.
const DEG_PER_TICK: &str = "deg_per_tick";

/// `cal` as JSON text for Python.
pub(crate) fn to_json(cal: &Calibration) -> Outcome<String> {
    let mut value = serde_json::to_value(cal).map_err(not_json)?;
    if let Some(joints) = value.get_mut("joints").and_then(|j| j.as_array_mut()) {
        for (out, joint) in joints.iter_mut().zip(&cal.joints) {
            let per_tick = joint.servo_model().map(|m| m.deg_per_tick());
            if let Some(map) = out.as_object_mut() {
                map.insert(DEG_PER_TICK.to_owned(), serde_json::json!(per_tick));
            }
        }
    }
    Ok(value.to_string())
}

/// A calibration from Python's JSON text.
fn from_json(text: &str) -> Outcome<Calibration> {
    let mut value: serde_json::Value = serde_json::from_str(text).map_err(bad_json)?;
    if let Some(joints) = value.get_mut("joints").and_then(|j| j.as_array_mut()) {
        for joint in joints {
            if let Some(map) = joint.as_object_mut() {
                map.remove(DEG_PER_TICK);
            }
        }
    }
    serde_json::from_value(value).map_err(bad_json)
}

fn not_json(e: serde_json::Error) -> Failure {
    Failure::new(
        Class::Error,
        format!("the calibration does not serialise: {e}"),
    )
}

fn bad_json(e: serde_json::Error) -> Failure {
    Failure::usage(format!("not a calibration: {e}"))
}

/// The calibration of `robot` (a robot file, a built-in name or YAML text)
/// that a LeRobot calibration file's JSON text `json` describes, as JSON.
#[pyfunction]
pub(crate) fn calibration_from_lerobot(
    py: Python<'_>,
    robot: &str,
    json: &str,
) -> PyResult<String> {
    Ok(py.allow_threads(|| -> Outcome<String> {
        let design = load_design(robot)?;
        let cal = from_lerobot(&design, json, "imported from LeRobot")
            .map_err(|e| Failure::new(Class::ConfigError, chain(&e)))?;
        to_json(&cal)
    })?)
}

/// The LeRobot calibration file (its JSON text) of `calibration` (JSON).
#[pyfunction]
pub(crate) fn calibration_to_lerobot(calibration: &str) -> PyResult<String> {
    Ok(to_lerobot(&from_json(calibration)?))
}

/// Writes `calibration` (JSON) to `path` as a servobus calibration file,
/// replacing it whole or not at all.
#[pyfunction]
pub(crate) fn save_calibration(py: Python<'_>, calibration: &str, path: &str) -> PyResult<()> {
    let cal = from_json(calibration)?;
    py.allow_threads(|| servobus_config::save_calibration(&cal, Path::new(path)))
        .map_err(|e| {
            Failure::new(Class::Error, chain(&e)).with("file", Field::Str(path.to_owned()))
        })?;
    Ok(())
}

/// The calibration file at `path`, as JSON.
#[pyfunction]
pub(crate) fn load_calibration(py: Python<'_>, path: &str) -> PyResult<String> {
    Ok(py.allow_threads(|| -> Outcome<String> {
        let cal = servobus_config::load_calibration(Path::new(path))?;
        to_json(&cal)
    })?)
}

/// The Python caller as the procedure's operator: it never presses Enter
/// (each step ends once the joints have moved and been held still), is
/// told each step through `on_step(name)`, and Ctrl-C (or an exception in
/// `on_step`) ends every step at once, the exception kept to be raised.
struct Unattended {
    on_step: Option<PyObject>,
    stopped_by: Option<PyErr>,
}

impl Unattended {
    /// Runs `f` with the GIL unless an exception has stopped the procedure;
    /// keeps the exception `f` raises.
    fn with_python(&mut self, f: impl FnOnce(Python<'_>, Option<&PyObject>) -> PyResult<()>) {
        if self.stopped_by.is_some() {
            return;
        }
        let on_step = self.on_step.as_ref();
        if let Err(e) = Python::with_gil(|py| f(py, on_step)) {
            self.stopped_by = Some(e);
        }
    }
}

impl Operator for Unattended {
    fn step(&mut self, step: Step) {
        let name = match step {
            Step::TorqueOff => "torque_off",
            Step::HoldPose => "hold_pose",
            Step::Sweep => "sweep",
            Step::Done => "done",
        };
        self.with_python(|py, on_step| match on_step {
            Some(callback) => callback.call1(py, (name,)).map(drop),
            None => Ok(()),
        });
    }

    fn watch(&mut self, _at: Duration, _joints: &[LiveJoint]) {}

    fn confirmed(&mut self) -> bool {
        self.with_python(|py, _| py.check_signals());
        self.stopped_by.is_some()
    }
}

/// Where and how [`calibrate_robot`] calibrates.
pub(crate) struct Where<'a> {
    /// The first bus's port; None: the built-in simulator, in virtual time.
    pub port: Option<&'a str>,
    /// On the simulator: the hand that moves the joints (a file or a
    /// built-in name), and how the servos are mounted.
    pub hand: Option<&'a str>,
    /// See `hand`.
    pub mounting: Option<&'a str>,
    /// A step that has not ended after this many seconds fails.
    pub timeout: f64,
    /// Called with each step's name as it begins.
    pub on_step: Option<PyObject>,
}

/// What [`calibrate_robot`] gives: the calibration, or why there is none;
/// an exception (Ctrl-C's, or one `on_step` raised) that stopped the
/// procedure comes first.
pub(crate) enum Calibrated {
    /// The calibration, or the procedure's failure.
    Taken(Outcome<Calibration>),
    /// The exception that stopped it.
    Stopped(PyErr),
}

/// Runs the calibration procedure of `servobus calibrate` (unattended:
/// each step ends once the robot has moved and been held still) on
/// `robot` (as designed), at `at`. Call it without the GIL.
pub(crate) fn calibrate_robot(robot: &str, mut at: Where<'_>) -> Calibrated {
    let mut operator = Unattended {
        on_step: at.on_step.take(),
        stopped_by: None,
    };
    let taken = measure(robot, &at, &mut operator);
    match operator.stopped_by {
        Some(e) => Calibrated::Stopped(e),
        None => Calibrated::Taken(taken),
    }
}

/// The procedure itself, with `operator`.
fn measure(robot: &str, at: &Where<'_>, operator: &mut Unattended) -> Outcome<Calibration> {
    let timeout = crate::checks::timeout("timeout", at.timeout)?;
    let design = load_design(robot)?;
    let options = ProcedureOptions {
        auto: true,
        timeout,
        taken: servobus_config::utc_now(),
        ..ProcedureOptions::default()
    };
    let measured = match at.port {
        None => {
            if at.hand.is_none() {
                return Err(Failure::usage(
                    "on the simulator nobody moves the joints: give the hand that does \
                     (e.g. hand=\"so101-first-arm-hand\")",
                ));
            }
            let sim = with_bodies(SimRobot::builder(&design), at.mounting, at.hand)?.build()?;
            calibrate(&design, &mut sim.driver_buses(), operator, &options)
        }
        Some(port) => {
            let ports = every_port(&design, &[port]).required(&design)?;
            let patient = Allowance::AtLeast(PATIENCE);
            let mut buses = open_buses(&design, &ports, patient, Some(PATIENT_RETRIES))?;
            calibrate(&design, &mut buses, operator, &options)
        }
    };
    measured.map_err(|e| Failure::new(Class::CalibrationError, chain(&e)))
}

/// Registers the module's calibration functions.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(calibration_from_lerobot, m)?)?;
    m.add_function(wrap_pyfunction!(calibration_to_lerobot, m)?)?;
    m.add_function(wrap_pyfunction!(save_calibration, m)?)?;
    m.add_function(wrap_pyfunction!(load_calibration, m)?)?;
    Ok(())
}
