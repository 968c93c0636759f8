//! Rust errors as the Python exceptions of `servobus._errors`, all under
//! `servobus.Error`, each with its fields as attributes.

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use servobus_config::ConfigError;
use servobus_robot::bus::BusError;

/// A field of an exception: a Python attribute.
#[derive(Debug, Clone)]
pub(crate) enum Field {
    /// A text.
    Str(String),
    /// A whole number.
    Int(i64),
    /// A real number.
    Float(f64),
}

/// The Python exception classes of `servobus._errors` a failure is raised
/// as (a test checks each is defined there).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Class {
    /// `servobus.Error`: the base of them all.
    Error,
    /// A robot, motion or calibration file that is invalid or unreadable.
    ConfigError,
    /// A port that cannot be opened or failed.
    PortError,
    /// Servos that do not match the calibration, or a calibration that
    /// could not be measured.
    CalibrationError,
    /// A servo that did not answer as asked.
    MissingServo,
    /// A servo that did not answer at all.
    TimeoutError,
    /// A value beyond a register's or a joint's limits.
    LimitError,
    /// A bad argument.
    UsageError,
}

impl Class {
    /// Every class.
    #[cfg(test)]
    const ALL: [Class; 8] = [
        Class::Error,
        Class::ConfigError,
        Class::PortError,
        Class::CalibrationError,
        Class::MissingServo,
        Class::TimeoutError,
        Class::LimitError,
        Class::UsageError,
    ];

    /// The class's name in `servobus._errors`.
    fn name(self) -> &'static str {
        match self {
            Class::Error => "Error",
            Class::ConfigError => "ConfigError",
            Class::PortError => "PortError",
            Class::CalibrationError => "CalibrationError",
            Class::MissingServo => "MissingServo",
            Class::TimeoutError => "TimeoutError",
            Class::LimitError => "LimitError",
            Class::UsageError => "UsageError",
        }
    }
}

/// Why a call failed: its Python exception class, its message and its
/// fields.
#[derive(Debug, Clone)]
pub(crate) struct Failure {
    class: Class,
    message: String,
    fields: Vec<(&'static str, Field)>,
}

/// What the extension's functions return.
pub(crate) type Outcome<T> = Result<T, Failure>;

impl Failure {
    /// A failure raised as `servobus.<class>` with `message`.
    pub(crate) fn new(class: Class, message: impl Into<String>) -> Self {
        Failure {
            class,
            message: message.into(),
            fields: Vec::new(),
        }
    }

    /// A bad argument (`servobus.UsageError`, also a `ValueError`).
    pub(crate) fn usage(message: impl Into<String>) -> Self {
        Failure::new(Class::UsageError, message)
    }

    /// Adds the attribute `name`.
    pub(crate) fn with(mut self, name: &'static str, value: Field) -> Self {
        self.fields.push((name, value));
        self
    }

    /// The Python exception, made with the GIL held.
    fn to_py(&self, py: Python<'_>) -> PyErr {
        let made = (|| -> PyResult<PyErr> {
            let class = py.import("servobus._errors")?.getattr(self.class.name())?;
            let kwargs = PyDict::new(py);
            for (name, value) in &self.fields {
                match value {
                    Field::Str(s) => kwargs.set_item(name, s)?,
                    Field::Int(i) => kwargs.set_item(name, i)?,
                    Field::Float(f) => kwargs.set_item(name, f)?,
                }
            }
            let exception = class.call((self.message.as_str(),), Some(&kwargs))?;
            Ok(PyErr::from_value(exception))
        })();
        made.unwrap_or_else(|why| {
            PyRuntimeError::new_err(format!("{} (and {why} making its exception)", self.message))
        })
    }
}

impl From<Failure> for PyErr {
    fn from(f: Failure) -> PyErr {
        Python::with_gil(|py| f.to_py(py))
    }
}

impl From<ConfigError> for Failure {
    fn from(e: ConfigError) -> Self {
        let message = e.to_string();
        match e {
            ConfigError::Invalid {
                file,
                line,
                column,
                field,
                ..
            } => Failure::new(Class::ConfigError, message)
                .with("file", Field::Str(file.display().to_string()))
                .with("line", Field::Int(line as i64))
                .with("column", Field::Int(column as i64))
                .with("field", Field::Str(field)),
            ConfigError::Read { path, .. } | ConfigError::TooLarge { path, .. } => {
                Failure::new(Class::ConfigError, message)
                    .with("file", Field::Str(path.display().to_string()))
            }
            _ => Failure::new(Class::ConfigError, message),
        }
    }
}

/// A servo that did not answer as asked (`MissingServo`, or its subclass
/// `TimeoutError` for no reply at all).
fn missing(class: Class, message: String, id: u8, reason: &str) -> Failure {
    Failure::new(class, message)
        .with("id", Field::Int(i64::from(id)))
        .with("reason", Field::Str(reason.to_owned()))
}

impl From<BusError> for Failure {
    fn from(e: BusError) -> Self {
        let message = e.to_string();
        match e {
            BusError::Timeout { id, .. } => missing(Class::TimeoutError, message, id, "no reply"),
            BusError::Corrupt { id } => {
                missing(Class::MissingServo, message, id, "corrupted reply")
            }
            BusError::WrongId { expected, .. } => missing(
                Class::MissingServo,
                message,
                expected,
                "reply from another ID",
            ),
            BusError::WrongLength { id, .. } => missing(
                Class::MissingServo,
                message,
                id,
                "reply of the wrong length",
            ),
            BusError::Value(servobus_protocol::registers::ValueError::OutOfRange {
                value,
                min,
                max,
                ..
            }) => Failure::new(Class::LimitError, message)
                .with("value", Field::Float(f64::from(value)))
                .with("min", Field::Float(f64::from(min)))
                .with("max", Field::Float(f64::from(max))),
            BusError::DuplicateId { .. }
            | BusError::IdOutOfRange { .. }
            | BusError::ReadOnly { .. }
            | BusError::WrongSeries { .. }
            | BusError::Encode(_)
            | BusError::InvalidRequest(_)
            | BusError::BufferLength { .. } => Failure::usage(message),
            BusError::Transport(_) => Failure::new(Class::PortError, message),
            _ => Failure::new(Class::Error, message),
        }
    }
}

impl From<servobus_robot::ports::OpenError> for Failure {
    fn from(e: servobus_robot::ports::OpenError) -> Self {
        use servobus_robot::ports::OpenError;
        let port = match &e {
            OpenError::Bus { port, .. } | OpenError::Port { port, .. } => port.clone(),
            _ => String::new(),
        };
        Failure::new(Class::PortError, chain(&e)).with("port", Field::Str(port))
    }
}

impl From<servobus_robot::Error> for Failure {
    fn from(e: servobus_robot::Error) -> Self {
        use servobus_robot::Error;
        match e {
            Error::Config(c) => c.into(),
            Error::Open(o) => o.into(),
            Error::NoPort { .. } | Error::TooManyPorts { .. } => {
                Failure::new(Class::PortError, e.to_string())
            }
            Error::Refused { ref port, .. } => {
                let port = port.clone();
                Failure::new(Class::CalibrationError, chain(&e)).with("port", Field::Str(port))
            }
            Error::Run(r) => r.into(),
            other => Failure::new(Class::Error, chain(&other)),
        }
    }
}

impl From<servobus_robot::RunError> for Failure {
    fn from(e: servobus_robot::RunError) -> Self {
        Failure::new(Class::Error, chain(&e))
    }
}

impl From<servobus_robot::sim::SimRobotError> for Failure {
    fn from(e: servobus_robot::sim::SimRobotError) -> Self {
        Failure::new(Class::ConfigError, chain(&e))
    }
}

impl From<servobus_robot::sim::PtyError> for Failure {
    fn from(e: servobus_robot::sim::PtyError) -> Self {
        Failure::new(Class::PortError, chain(&e))
    }
}

/// An error's message followed by those of its sources.
pub(crate) fn chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        let more = s.to_string();
        if !text.contains(&more) {
            text.push_str(": ");
            text.push_str(&more);
        }
        source = s.source();
    }
    text
}

/// A lock whose holder panicked: the object is no longer usable.
pub(crate) fn poisoned<T>(_: T) -> Failure {
    Failure::new(
        Class::Error,
        "an earlier call panicked while using this object",
    )
}

#[cfg(test)]
mod tests {
    use super::Class;

    /// Each class a failure can be raised as is defined in `_errors.py`,
    /// under `Error`.
    #[test]
    fn every_class_is_defined_in_the_python_errors() {
        let python = include_str!("../servobus/_errors.py");
        for class in Class::ALL {
            let name = class.name();
            let defined = python.lines().any(|l| {
                l.strip_prefix("class ")
                    .and_then(|rest| rest.strip_prefix(name))
                    .is_some_and(|rest| rest.starts_with('(') || rest.starts_with(':'))
            });
            assert!(defined, "class {name} is not in servobus/_errors.py");
        }
    }
}
