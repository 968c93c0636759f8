//! `servobus.Bus`: one bus of Feetech servos, on a serial port or on the
//! in-process simulator, read and written by register name.

use std::sync::Mutex;
use std::time::Duration;

use pyo3::prelude::*;
use servobus_protocol::MAX_ID;
use servobus_robot::bus::registers::{read_uint, write_uint, Register};
use servobus_robot::bus::{Bus as DriverBus, Series, SystemClock, PROBE_CEILING, PROBE_PINGS};
use servobus_robot::ports::{open_plain_bus, system_clock, SerialBus};
use servobus_robot::sim::SimRobot;
use servobus_robot::sim::WallBus;

use crate::checks;
use crate::errors::{poisoned, Class, Failure, Field, Outcome};
use crate::load::load_robot;

/// The in-process simulator's bus, paced by the wall clock.
type SimDriverBus = DriverBus<WallBus<SystemClock>>;

/// A bus of either kind.
enum AnyBus {
    /// A serial port (real servos, or a `servobus sim` pty).
    Serial(SerialBus),
    /// The in-process simulator.
    Sim(SimDriverBus),
}

/// Runs `$body` with `$b` bound to the driver bus, whatever its kind.
macro_rules! on_bus {
    ($bus:expr, $b:ident => $body:expr) => {
        match $bus {
            AnyBus::Serial($b) => $body,
            AnyBus::Sim($b) => $body,
        }
    };
}

/// A SYNC READ as Python gets it: `(id, value or None)` per servo asked,
/// and `(id, why, attempts)` per servo missing.
type SyncReadLists = (Vec<(u8, Option<i32>)>, Vec<(u8, String, u8)>);

/// A raw SYNC READ as Python gets it (unsigned numbers).
type RawSyncReadLists = (Vec<(u8, Option<u32>)>, Vec<(u8, String, u8)>);

/// A raw access's length: 1, 2 or 4 bytes.
fn raw_length(length: &Bound<'_, PyAny>) -> Outcome<usize> {
    match checks::whole(length, "length", 1, 4) {
        Ok(n @ (1 | 2 | 4)) => Ok(n as usize),
        _ => Err(Failure::usage(format!(
            "length {}: give 1, 2 or 4 bytes",
            shown(length)
        ))),
    }
}

/// A register address from Python: 0..=255.
fn raw_address(address: &Bound<'_, PyAny>) -> Outcome<u8> {
    let a = checks::whole(address, "address", 0, i64::from(u8::MAX)).map_err(|_| {
        Failure::usage(format!(
            "address {}: a register address is 0..=255",
            shown(address)
        ))
    })?;
    // Within 0..=255 by the check above.
    Ok(a as u8)
}

/// How a Python value shows in a message.
fn shown(value: &Bound<'_, PyAny>) -> String {
    value
        .str()
        .map(|s| s.to_string())
        .unwrap_or_else(|_| "?".to_owned())
}

/// An unsigned raw value from Python for `length` bytes.
fn raw_value(value: &Bound<'_, PyAny>, length: usize) -> Outcome<u32> {
    let max = if length == 4 {
        u32::MAX
    } else {
        (1u32 << (8 * length)) - 1
    };
    match value.extract::<i64>() {
        Ok(v) if (0..=i64::from(max)).contains(&v) => Ok(v as u32),
        _ => Err(Failure::new(
            Class::LimitError,
            format!("value {} does not fit {length} byte(s)", shown(value)),
        )
        .with("value", Field::Float(as_float(value)))
        .with("min", Field::Float(0.0))
        .with("max", Field::Float(f64::from(max)))),
    }
}

/// A Python number as a float (NaN when it is not one), for an error's
/// `value` field.
fn as_float(value: &Bound<'_, PyAny>) -> f64 {
    value.extract::<f64>().unwrap_or(f64::NAN)
}

/// Runs `f` without the GIL, then acts on a signal that came meanwhile:
/// Ctrl-C raises `KeyboardInterrupt` from the call it came during, whatever
/// the call's result (the driver sits through `EINTR` to each deadline, so
/// a transaction is never cut in half and the signal is seen here).
fn blocking<R: Send>(py: Python<'_>, f: impl Send + FnOnce() -> Outcome<R>) -> PyResult<R> {
    let result = py.allow_threads(f);
    py.check_signals()?;
    Ok(result?)
}

/// `value` as `length` bytes in the byte order of `series`.
fn raw_bytes(value: u32, length: usize, series: Series) -> Outcome<Vec<u8>> {
    let max = if length == 4 {
        u32::MAX
    } else {
        (1u32 << (8 * length)) - 1
    };
    if value > max {
        return Err(Failure::new(
            Class::LimitError,
            format!("value {value} does not fit {length} byte(s)"),
        )
        .with("value", Field::Float(f64::from(value)))
        .with("min", Field::Float(0.0))
        .with("max", Field::Float(f64::from(max))));
    }
    let mut bytes = vec![0u8; length];
    write_uint(value, series.byte_order(), &mut bytes);
    Ok(bytes)
}

/// A bus of Feetech servos: `Bus(port, baud=1_000_000, series="sts")`.
///
/// Registers are named as in the servos' control table
/// (`present_position`, `goal_position`, `torque_enable`, ...); values are
/// the register's raw units (ticks for positions). Every call releases the
/// GIL while it waits on the bus.
#[pyclass(module = "servobus._native", name = "Bus")]
pub struct Bus {
    inner: Mutex<Option<AnyBus>>,
    series: Series,
    label: String,
}

/// The series named `name` (`sts`, `sms` or `scs`).
pub(crate) fn series_of(name: &str) -> Outcome<Series> {
    match name.to_ascii_lowercase().as_str() {
        "sts" | "sms" | "sts/sms" => Ok(Series::Sts),
        "scs" => Ok(Series::Scs),
        _ => Err(Failure::usage(format!(
            "series `{name}`: give \"sts\" (STS/SMS) or \"scs\""
        ))),
    }
}

/// The name Python gives `series`.
fn series_name(series: Series) -> &'static str {
    match series {
        Series::Scs => "scs",
        _ => "sts",
    }
}

/// The register `name` of `series`.
fn register(series: Series, name: &str) -> Outcome<&'static Register> {
    series.map().get(name).ok_or_else(|| {
        Failure::usage(format!(
            "no register named `{name}` on {} servos",
            series_name(series)
        ))
    })
}

/// A servo ID from Python: 0..=253.
fn servo_id(id: &Bound<'_, PyAny>) -> Outcome<u8> {
    let id = checks::whole(id, "ID", 0, i64::from(MAX_ID))
        .map_err(|_| Failure::usage(format!("ID {}: a servo's ID is 0..=253", shown(id))))?;
    // Within 0..=253 by the check above.
    Ok(id as u8)
}

/// A value of `reg` from Python: a whole number within the register's
/// range, or `LimitError` with the range (NaN, inf and 1e30 included).
fn value_of(value: &Bound<'_, PyAny>, reg: &Register, series: Series) -> Outcome<i32> {
    let fits = value
        .extract::<i64>()
        .ok()
        .and_then(|v| i32::try_from(v).ok());
    if let Some(v) = fits {
        return Ok(v);
    }
    let mut failure = Failure::new(
        Class::LimitError,
        format!(
            "{}: {} is not a value the register can hold",
            reg.name,
            shown(value)
        ),
    )
    .with("value", Field::Float(as_float(value)));
    if let Some((min, max)) = register_range(reg, series) {
        failure = failure
            .with("min", Field::Float(f64::from(min)))
            .with("max", Field::Float(f64::from(max)));
    }
    Err(failure)
}

/// The values `reg` holds, as its encoder says when asked for the most
/// extreme ones.
fn register_range(reg: &Register, series: Series) -> Option<(i32, i32)> {
    let mut block = [0u8; 4];
    let block = block.get_mut(..usize::from(reg.size))?;
    match reg.encode(i32::MAX, series.byte_order(), block) {
        Err(servobus_protocol::registers::ValueError::OutOfRange { min, max, .. }) => {
            Some((min, max))
        }
        _ => None,
    }
}

impl Bus {
    /// PINGs servo `id`: whether it answered (call without the GIL).
    fn ping_one(&self, id: u8) -> Outcome<bool> {
        self.with(|bus| {
            on_bus!(bus, b => match b.ping(id) {
                Ok(_) => Ok(true),
                Err(e) if e.is_timeout() => Ok(false),
                Err(e) => Err(e.into()),
            })
        })
    }

    /// Runs `f` on the open bus with the lock held (call without the GIL).
    fn with<R>(&self, f: impl FnOnce(&mut AnyBus) -> Outcome<R>) -> Outcome<R> {
        let mut guard = self.inner.lock().map_err(poisoned)?;
        match guard.as_mut() {
            Some(bus) => f(bus),
            None => Err(Failure::new(
                Class::Error,
                format!("{} is closed", self.label),
            )),
        }
    }
}

#[pymethods]
impl Bus {
    /// Opens `port` at `baud` for servos of `series` (`"sts"` for STS/SMS,
    /// `"scs"`). `latency` (s) is the adapter's reply latency the deadlines
    /// allow; by default what the port is assumed to need.
    #[new]
    #[pyo3(signature = (port, baud=None, series="sts", latency=None))]
    fn new(
        py: Python<'_>,
        port: String,
        baud: Option<&Bound<'_, PyAny>>,
        series: &str,
        latency: Option<f64>,
    ) -> PyResult<Self> {
        // None: the servos' factory rate, 1 Mbps.
        let baud = baud.map_or(
            Ok(servobus_protocol::registers::MAX_SERVO_BAUD),
            checks::baud,
        )?;
        let series = series_of(series)?;
        let latency = latency.map(checks::latency).transpose()?;
        let bus = py
            .allow_threads(|| open_plain_bus(&port, baud, series, latency))
            .map_err(Failure::from)?;
        Ok(Bus {
            inner: Mutex::new(Some(AnyBus::Serial(bus))),
            series,
            label: format!("the bus on {port}"),
        })
    }

    /// An in-process simulated bus serving the servos of `robot` (a robot
    /// file, a built-in name such as `"so101"`, or YAML text); its first
    /// bus, each shaft at its joint's rest position, in real time.
    #[staticmethod]
    #[pyo3(signature = (robot="so101"))]
    fn sim(py: Python<'_>, robot: &str) -> PyResult<Self> {
        let bus = py.allow_threads(|| -> Outcome<SimDriverBus> {
            let robot = load_robot(robot, None)?;
            let config = robot.config();
            let sim = SimRobot::builder(config).build()?;
            sim.wall_buses(&system_clock())
                .into_iter()
                .next()
                .ok_or_else(|| Failure::new(Class::ConfigError, "the robot has no bus"))
        })?;
        let series = bus.settings().series;
        Ok(Bus {
            inner: Mutex::new(Some(AnyBus::Sim(bus))),
            series,
            label: "the simulated bus".to_owned(),
        })
    }

    /// The series whose registers the bus reads: `"sts"` or `"scs"`.
    #[getter]
    fn series(&self) -> &'static str {
        series_name(self.series)
    }

    /// The physical unit of `register`'s values and the scale from its raw
    /// number to it: `(0.1, "V")` for `present_voltage`, `(1.0, "ticks")`
    /// for a position, `(1.0, "")` for a plain number (see the control
    /// table's units).
    fn unit(&self, register: &str) -> PyResult<(f64, &'static str)> {
        Ok(crate::units::physical(self::register(
            self.series,
            register,
        )?))
    }

    /// PING servo `id`: True when it answers, False when nothing answered.
    fn ping(&self, py: Python<'_>, id: &Bound<'_, PyAny>) -> PyResult<bool> {
        let id = servo_id(id)?;
        blocking(py, || self.ping_one(id))
    }

    /// The IDs among `ids` (default every ID, 0..=253) that answer a PING,
    /// in increasing order. Ctrl-C between two PINGs raises
    /// `KeyboardInterrupt`.
    #[pyo3(signature = (ids=None))]
    fn scan(&self, py: Python<'_>, ids: Option<Vec<Bound<'_, PyAny>>>) -> PyResult<Vec<u16>> {
        let ids: Vec<u8> = match ids {
            Some(ids) => ids.iter().map(servo_id).collect::<Outcome<_>>()?,
            None => (0..=MAX_ID).collect(),
        };
        let mut found = Vec::new();
        for id in ids {
            if blocking(py, || self.ping_one(id))? {
                found.push(id);
            }
        }
        found.sort_unstable();
        found.dedup();
        // Numbers for Python: a list of u8 would become bytes.
        Ok(found.into_iter().map(u16::from).collect())
    }

    /// Reads the register `register` of servo `id`: its value (signed
    /// registers signed). Raises `TimeoutError` when the servo does not
    /// answer.
    fn read(&self, py: Python<'_>, id: &Bound<'_, PyAny>, register: &str) -> PyResult<i32> {
        let id = servo_id(id)?;
        let reg = self::register(self.series, register)?;
        blocking(py, || {
            self.with(|bus| on_bus!(bus, b => Ok(b.read_register(id, reg)?.0)))
        })
    }

    /// Writes `value` to the register `register` of servo `id` (an EEPROM
    /// register persistently: unlock, write, verify, lock). Raises
    /// `LimitError` for a value the register cannot hold.
    fn write(
        &self,
        py: Python<'_>,
        id: &Bound<'_, PyAny>,
        register: &str,
        value: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let id = servo_id(id)?;
        let reg = self::register(self.series, register)?;
        let value = value_of(value, reg, self.series)?;
        blocking(py, || {
            self.with(|bus| {
                on_bus!(bus, b => {
                    b.write_register(id, reg, value)?;
                    Ok(())
                })
            })
        })
    }

    /// Reads `register` of every servo in `ids` with one SYNC READ (and
    /// one more for the servos missing from it, as a READ is retried): a
    /// list of `(id, value or None)` in the order of `ids`, and a list of
    /// `(id, why, attempts)` for the servos that did not answer. A missing
    /// servo never costs the others' values.
    fn sync_read(
        &self,
        py: Python<'_>,
        register: &str,
        ids: Vec<Bound<'_, PyAny>>,
    ) -> PyResult<SyncReadLists> {
        let ids: Vec<u8> = ids.iter().map(servo_id).collect::<Outcome<_>>()?;
        let reg = self::register(self.series, register)?;
        let order = self.series.byte_order();
        blocking(py, || {
            self.with(|bus| {
                on_bus!(bus, b => {
                    // Servos missing from the first round are asked again, as
                    // many times as a READ is retried.
                    let read = b.sync_read_within(reg.address, reg.size, &ids, Duration::MAX)?;
                    let mut values = Vec::with_capacity(ids.len());
                    let mut missing = Vec::new();
                    for result in read.iter() {
                        match result {
                            Ok(reply) => {
                                let value = reg.decode(reply.data, order).ok();
                                values.push((reply.id, value));
                            }
                            Err(m) => {
                                values.push((m.id, None));
                                missing.push((m.id, m.reason.to_string(), m.attempts));
                            }
                        }
                    }
                    Ok((values, missing))
                })
            })
        })
    }

    /// Writes `register` of several servos with one SYNC WRITE:
    /// `values` maps each servo's ID to its value. Nobody answers.
    fn sync_write(
        &self,
        py: Python<'_>,
        register: &str,
        values: Vec<(Bound<'_, PyAny>, Bound<'_, PyAny>)>,
    ) -> PyResult<()> {
        let reg = self::register(self.series, register)?;
        if !reg.access.is_writable() {
            return Err(Failure::usage(format!("register `{}` is read-only", reg.name)).into());
        }
        let order = self.series.byte_order();
        let size = usize::from(reg.size);
        let mut ids = Vec::with_capacity(values.len());
        let mut data = vec![0u8; values.len() * size];
        for ((id, value), block) in values.iter().zip(data.chunks_mut(size)) {
            ids.push(servo_id(id)?);
            reg.encode(value_of(value, reg, self.series)?, order, block)
                .map_err(|e| Failure::from(servobus_robot::bus::BusError::Value(e)))?;
        }
        if ids.is_empty() {
            return Ok(());
        }
        blocking(py, || {
            self.with(|bus| {
                on_bus!(bus, b => {
                    b.sync_write(reg.address, &ids, &data)?;
                    Ok(())
                })
            })
        })
    }

    /// Reads `length` (1, 2 or 4) bytes at `address` (0..=255) of servo
    /// `id` as one unsigned number in the bus's byte order, for clients
    /// with control tables of their own (LeRobot): `(value, status flags)`.
    /// Raises `UsageError` for an address, length or ID out of range.
    fn read_raw(
        &self,
        py: Python<'_>,
        id: &Bound<'_, PyAny>,
        address: &Bound<'_, PyAny>,
        length: &Bound<'_, PyAny>,
    ) -> PyResult<(u32, u8)> {
        let id = servo_id(id)?;
        let address = raw_address(address)?;
        let length = raw_length(length)?;
        let order = self.series.byte_order();
        blocking(py, || {
            self.with(|bus| {
                on_bus!(bus, b => {
                    let mut buf = [0u8; 4];
                    let flags = b.read(id, address, &mut buf[..length])?;
                    Ok((read_uint(&buf[..length], order), flags.0))
                })
            })
        })
    }

    /// Writes `value` as `length` (1, 2 or 4) bytes at `address` of servo
    /// `id` with a plain WRITE: the reply's status flags, or None when the
    /// servo sends none. Raises `LimitError` for a value the bytes cannot
    /// hold.
    fn write_raw(
        &self,
        py: Python<'_>,
        id: &Bound<'_, PyAny>,
        address: &Bound<'_, PyAny>,
        length: &Bound<'_, PyAny>,
        value: &Bound<'_, PyAny>,
    ) -> PyResult<Option<u8>> {
        let id = servo_id(id)?;
        let address = raw_address(address)?;
        let length = raw_length(length)?;
        let bytes = raw_bytes(raw_value(value, length)?, length, self.series)?;
        blocking(py, || {
            self.with(|bus| on_bus!(bus, b => Ok(b.write(id, address, &bytes)?.map(|f| f.0))))
        })
    }

    /// As `sync_read`, by address and length (1, 2 or 4) instead of a
    /// register name: unsigned numbers in the bus's byte order.
    fn sync_read_raw(
        &self,
        py: Python<'_>,
        address: &Bound<'_, PyAny>,
        length: &Bound<'_, PyAny>,
        ids: Vec<Bound<'_, PyAny>>,
    ) -> PyResult<RawSyncReadLists> {
        let ids: Vec<u8> = ids.iter().map(servo_id).collect::<Outcome<_>>()?;
        let address = raw_address(address)?;
        let length = raw_length(length)?;
        let order = self.series.byte_order();
        blocking(py, || {
            self.with(|bus| on_bus!(bus, b => {
                // The length is 1, 2 or 4: it fits a byte.
                let len = length as u8;
                let read = b.sync_read_within(address, len, &ids, Duration::MAX)?;
                let mut values = Vec::with_capacity(ids.len());
                let mut missing = Vec::new();
                for result in read.iter() {
                    match result {
                        Ok(reply) => values.push((reply.id, Some(read_uint(reply.data, order)))),
                        Err(m) => {
                            values.push((m.id, None));
                            missing.push((m.id, m.reason.to_string(), m.attempts));
                        }
                    }
                }
                Ok((values, missing))
            }))
        })
    }

    /// As `sync_write`, by address and length (1, 2 or 4): `values` are
    /// `(id, unsigned number)` pairs.
    fn sync_write_raw(
        &self,
        py: Python<'_>,
        address: &Bound<'_, PyAny>,
        length: &Bound<'_, PyAny>,
        values: Vec<(Bound<'_, PyAny>, Bound<'_, PyAny>)>,
    ) -> PyResult<()> {
        let address = raw_address(address)?;
        let length = raw_length(length)?;
        let mut ids = Vec::with_capacity(values.len());
        let mut data = Vec::with_capacity(values.len() * length);
        for (id, value) in &values {
            ids.push(servo_id(id)?);
            data.extend_from_slice(&raw_bytes(raw_value(value, length)?, length, self.series)?);
        }
        if ids.is_empty() {
            return Ok(());
        }
        blocking(py, || {
            self.with(|bus| {
                on_bus!(bus, b => {
                    b.sync_write(address, &ids, &data)?;
                    Ok(())
                })
            })
        })
    }

    /// The adapter latency (s) the reply deadlines allow now.
    #[getter]
    fn latency(&self, py: Python<'_>) -> PyResult<f64> {
        blocking(py, || {
            self.with(|bus| on_bus!(bus, b => Ok(b.settings().link.latency.as_secs_f64())))
        })
    }

    /// Learns the link: measures the adapter's latency with PINGs of the
    /// servos `ids` in turn (as a live run with `latency_us: auto` does at
    /// start-up) and raises the reply deadlines' allowance to the most
    /// seen, if that is more than they allow now (never lowers it). Returns
    /// the latency allowed, s. A servo that does not answer is passed over.
    fn learn_latency(&self, py: Python<'_>, ids: Vec<Bound<'_, PyAny>>) -> PyResult<f64> {
        let ids: Vec<u8> = ids.iter().map(servo_id).collect::<Outcome<_>>()?;
        if ids.is_empty() {
            return Err(Failure::usage("learn_latency: give the IDs of servos to PING").into());
        }
        blocking(py, || {
            self.with(|bus| {
                on_bus!(bus, b => {
                    let now = b.settings().link.latency;
                    let seen = b.probe_latency(&ids, PROBE_PINGS, PROBE_CEILING, |_| {})?;
                    let allowed = now.max(seen.max);
                    b.set_latency(allowed);
                    Ok(allowed.as_secs_f64())
                })
            })
        })
    }

    /// Closes the bus (its port is free for others); later calls raise.
    /// (`servobus.Bus`, the Python class around this one, is the context
    /// manager.)
    fn close(&self, py: Python<'_>) -> PyResult<()> {
        py.allow_threads(|| -> Outcome<()> {
            self.inner.lock().map_err(poisoned)?.take();
            Ok(())
        })?;
        Ok(())
    }

    fn __repr__(&self) -> String {
        format!("<servobus.Bus: {}>", self.label)
    }
}
