//! A joint's mode (`mode:`) and the settings written to its servo when a run
//! connects (`servo:`), checked against the register map of its model.
//!
//! | `servo:` key         | register             | the file's unit   | register unit   | accepted            |
//! |----------------------|----------------------|-------------------|-----------------|---------------------|
//! | `p`, `d`, `i`        | `p/d/i_coefficient`  | none              | none            | 0..=254             |
//! | `torque_limit`       | `torque_limit` (RAM) | % of full torque  | 0.1 %           | 0..=100             |
//! | `protection_current` | `protection_current` | mA                | 6.5 mA          | one step or more    |
//! | `acceleration`       | `acceleration` (RAM) | units/s^2         | 100 steps/s^2   | raw 1..=254         |
//! | `max_temperature`    | `max_temperature`    | degC              | degC            | 1..=255             |
//!
//! The coefficients, `protection_current` and `max_temperature` are EEPROM
//! registers ([`ServoWrite::eeprom`]).
//!
//! The register units are the ones the protocol crate's tables state; a
//! model whose table lacks a register, or states another unit for it, is
//! refused for that setting rather than sent a figure scaled for another
//! unit.

use servobus_protocol::registers::{Access, Model, Register, FASTEST_PROFILE};

use super::raw::RawServo;
use crate::Units;

/// What a joint's servo does with its target (`mode:` in the robot file).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[serde(expecting = "`position` or `wheel`")]
pub enum JointMode {
    /// Position control (operating mode 0 of register `mode`): the target
    /// is a position within `min`..`max`. The default.
    #[default]
    Position,
    /// Constant speed (operating mode 1 of register `mode`): the joint
    /// turns without end and its target is a speed, in units/s, within
    /// `max_velocity`; it has no position limits, offset or home.
    Wheel,
}

impl JointMode {
    /// The servo's operating mode (register `mode`, 33) this joint needs:
    /// 0 for a position joint, 1 for a wheel.
    pub const fn operating_mode(self) -> u8 {
        match self {
            JointMode::Position => 0,
            JointMode::Wheel => 1,
        }
    }
}

/// A joint's `servo:` settings, the values as the robot file gives them
/// (`None`: not given, the servo keeps its own), and the register writes
/// they make ([`ServoSettings::writes`]), checked against the joint's model
/// when the file is loaded. Built by loading a robot file.
#[derive(Debug, Clone, PartialEq)]
pub struct ServoSettings {
    /// Position loop P coefficient (register `p_coefficient`, 0..=254).
    pub p: Option<u8>,
    /// Position loop D coefficient (register `d_coefficient`, 0..=254).
    pub d: Option<u8>,
    /// Position loop I coefficient (register `i_coefficient`, 0..=254).
    pub i: Option<u8>,
    /// Torque ceiling, percent of the servo's full torque, 0..=100
    /// (register `torque_limit`, RAM, in 0.1 %).
    pub torque_limit: Option<f64>,
    /// Current above which the servo protects itself, mA (register
    /// `protection_current`, EEPROM, in 6.5 mA).
    pub protection_current: Option<f64>,
    /// The servo's own profile acceleration, robot units/s^2 (register
    /// `acceleration`, RAM, in 100 steps/s^2; never 0, which the servo
    /// reads as no limit).
    pub acceleration: Option<f64>,
    /// Overheat threshold, degC (register `max_temperature`, EEPROM).
    pub max_temperature: Option<u8>,
    /// Made from the fields above at load.
    writes: Vec<ServoWrite>,
}

/// One register write a joint's `servo:` settings make.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ServoWrite {
    /// The `servo:` key it comes from (`p`, `torque_limit`, ...).
    pub setting: &'static str,
    /// The register, from the joint's model's map.
    pub register: &'static Register,
    /// The raw register content, checked against the register's range.
    pub raw: u32,
    /// The register is in EEPROM: the write persists once the lock is
    /// open, so it is made only when asked (`--write-servos`); RAM
    /// registers are written at every connect.
    pub eeprom: bool,
}

impl ServoSettings {
    /// The register writes, in the order of the module's table: `p`, `d`,
    /// `i`, `torque_limit`, `protection_current`, `acceleration`,
    /// `max_temperature` (those given).
    pub fn writes(&self) -> &[ServoWrite] {
        &self.writes
    }

    /// The writes to RAM registers: made at every connect.
    pub fn ram_writes(&self) -> impl Iterator<Item = &ServoWrite> + '_ {
        self.writes.iter().filter(|w| !w.eeprom)
    }

    /// The writes to EEPROM registers: made only when asked.
    pub fn eeprom_writes(&self) -> impl Iterator<Item = &ServoWrite> + '_ {
        self.writes.iter().filter(|w| w.eeprom)
    }
}

/// Why a `servo:` setting was refused: the key and what is wrong.
#[derive(Debug)]
pub(super) struct Refusal {
    /// The `servo:` key.
    pub setting: &'static str,
    /// What is wrong and what is accepted.
    pub reason: String,
}

/// The largest gain the `servo:` keys `p`, `d`, `i` accept.
const MAX_GAIN: i64 = 254;

/// `raw` checked against `model` (angles in `units`).
pub(super) fn settings(
    raw: &RawServo,
    model: &'static Model,
    units: Units,
) -> Result<ServoSettings, Refusal> {
    let mut out = ServoSettings {
        p: None,
        d: None,
        i: None,
        torque_limit: raw.torque_limit,
        protection_current: raw.protection_current,
        acceleration: raw.acceleration,
        max_temperature: None,
        writes: Vec::new(),
    };
    for (key, register, given, slot) in [
        ("p", "p_coefficient", raw.p, &mut out.p),
        ("d", "d_coefficient", raw.d, &mut out.d),
        ("i", "i_coefficient", raw.i, &mut out.i),
    ] {
        if let Some(v) = given {
            let (write, gain) = gain(model, key, register, v)?;
            *slot = Some(gain);
            out.writes.push(write);
        }
    }
    if let Some(percent) = raw.torque_limit {
        out.writes.push(torque_limit(model, percent)?);
    }
    if let Some(ma) = raw.protection_current {
        out.writes.push(protection_current(model, ma)?);
    }
    if let Some(a) = raw.acceleration {
        out.writes.push(acceleration(model, units, a)?);
    }
    if let Some(c) = raw.max_temperature {
        let (write, c) = max_temperature(model, c)?;
        out.max_temperature = Some(c);
        out.writes.push(write);
    }
    Ok(out)
}

/// A position loop coefficient, 0..=[`MAX_GAIN`], and the gain as a byte.
fn gain(
    model: &'static Model,
    key: &'static str,
    register: &'static str,
    v: i64,
) -> Result<(ServoWrite, u8), Refusal> {
    let (reg, _) = lookup(model, key, register, "")?;
    let byte = u8::try_from(v).ok().filter(|&b| i64::from(b) <= MAX_GAIN);
    let Some(byte) = byte else {
        return Err(refusal(
            key,
            format!("must be a whole number from 0 to {MAX_GAIN}, got {v}"),
        ));
    };
    Ok((write(key, reg, f64::from(byte))?, byte))
}

fn torque_limit(model: &'static Model, percent: f64) -> Result<ServoWrite, Refusal> {
    const KEY: &str = "torque_limit";
    let (reg, step) = lookup(model, KEY, "torque_limit", "%")?;
    if !(percent.is_finite() && (0.0..=100.0).contains(&percent)) {
        return Err(refusal(
            KEY,
            format!("must be a percentage of the servo's torque from 0 to 100, got {percent}"),
        ));
    }
    write(KEY, reg, (percent / step).round())
}

fn protection_current(model: &'static Model, ma: f64) -> Result<ServoWrite, Refusal> {
    const KEY: &str = "protection_current";
    let (reg, step) = lookup(model, KEY, "protection_current", "mA")?;
    let raw = (ma / step).round();
    let (_, top) = reg.range();
    let top_ma = f64::from(top) * step;
    if !(ma.is_finite() && (1.0..=f64::from(top)).contains(&raw)) {
        return Err(refusal(
            KEY,
            format!(
                "must be a current in mA from {:.2} to {:.0} (the {} counts it in steps \
                 of {step} mA), got {ma}",
                up_to_hundredths(0.5 * step),
                top_ma.floor(),
                model.name
            ),
        ));
    }
    write(KEY, reg, raw)
}

fn acceleration(model: &'static Model, units: Units, a: f64) -> Result<ServoWrite, Refusal> {
    const KEY: &str = "acceleration";
    let (reg, step) = lookup(model, KEY, "acceleration", "steps/s^2")?;
    // Servo steps per robot unit: the same whether or not the joint is
    // calibrated (a calibration moves and may flip the scale, never
    // stretches it).
    let steps_per_unit = units.to_rad(1.0).to_degrees() / model.deg_per_tick();
    let unit_step = step / steps_per_unit;
    if a == 0.0 {
        return Err(refusal(
            KEY,
            format!(
                "0 tells the servo to accelerate without limit; give an acceleration in \
                 {units}/s^2 (one step is {unit_step:.2}), or leave it out to keep the servo's own"
            ),
        ));
    }
    let raw = (a / unit_step).round();
    if !(a.is_finite() && a > 0.0 && (1.0..=FASTEST_PROFILE).contains(&raw)) {
        return Err(refusal(
            KEY,
            format!(
                "must be from {:.2} to {:.1} {units}/s^2 (the {} counts it in steps of \
                 {step} steps/s^2, {unit_step:.2} {units}/s^2, up to {FASTEST_PROFILE}), got {a}",
                up_to_hundredths(0.5 * unit_step),
                (FASTEST_PROFILE * unit_step * 10.0).floor() / 10.0,
                model.name
            ),
        ));
    }
    write(KEY, reg, raw)
}

fn max_temperature(model: &'static Model, c: i64) -> Result<(ServoWrite, u8), Refusal> {
    const KEY: &str = "max_temperature";
    let (reg, _) = lookup(model, KEY, "max_temperature", "degC")?;
    let (_, top) = reg.range();
    let byte = u8::try_from(c)
        .ok()
        .filter(|&b| b >= 1 && i32::from(b) <= top);
    let Some(byte) = byte else {
        return Err(refusal(
            KEY,
            format!("must be a whole number of degC from 1 to {top}, got {c}"),
        ));
    };
    Ok((write(KEY, reg, f64::from(byte))?, byte))
}

/// The register `name` of `model` and the size of its unit's step, which
/// must count in `unit` (`""`: a plain number, step 1).
fn lookup(
    model: &'static Model,
    key: &'static str,
    name: &str,
    unit: &str,
) -> Result<(&'static Register, f64), Refusal> {
    let Some(reg) = model.map().get(name) else {
        return Err(refusal(
            key,
            format!(
                "the {} has no register `{name}`, so `{key}` cannot be set on it; remove it",
                model.name
            ),
        ));
    };
    if !reg.access.is_writable() {
        return Err(refusal(
            key,
            format!(
                "the {}'s register `{name}` is read-only, so `{key}` cannot be set on it; \
                 remove it",
                model.name
            ),
        ));
    }
    let Some(step) = unit_step(reg.unit, unit) else {
        let expected = if unit.is_empty() {
            "plain numbers"
        } else {
            unit
        };
        let stated = if reg.unit.is_empty() {
            "states no unit".to_owned()
        } else {
            format!("counts in `{}`", reg.unit)
        };
        return Err(refusal(
            key,
            format!(
                "`{key}` is converted for a register counting in {expected}, but the {}'s \
                 register `{name}` {stated}, so it cannot be set on it; remove it",
                model.name
            ),
        ));
    };
    Ok((reg, step))
}

/// The step of a register unit such as `6.5 mA` (6.5) or `%` (1) when it
/// counts in `unit`; `None` when it counts in anything else.
fn unit_step(stated: &str, unit: &str) -> Option<f64> {
    let stated = stated.trim();
    let (step, rest) = match stated.split_once(' ') {
        Some((step, rest)) => match step.parse::<f64>() {
            Ok(step) => (step, rest.trim()),
            Err(_) => (1.0, stated),
        },
        None => (1.0, stated),
    };
    (rest == unit && step.is_finite() && step > 0.0).then_some(step)
}

/// The write of `raw` (a whole number) to `reg`, checked against its range.
fn write(key: &'static str, reg: &'static Register, raw: f64) -> Result<ServoWrite, Refusal> {
    let (lo, hi) = reg.range();
    let fits = raw >= f64::from(lo) && raw <= f64::from(hi);
    // In range, the cast is exact: `raw` is a whole number of an i32 range.
    let value = if fits { Some(raw as i32) } else { None };
    match value.map(|v| reg.to_raw(v)) {
        Some(Ok(raw)) => Ok(ServoWrite {
            setting: key,
            register: reg,
            raw,
            eeprom: reg.access == Access::Eeprom,
        }),
        Some(Err(e)) => Err(refusal(key, e.to_string())),
        None => Err(refusal(
            key,
            format!(
                "makes {raw} for register `{}`, which holds {lo}..={hi}",
                reg.name
            ),
        )),
    }
}

/// `v` rounded up to hundredths: a lowest accepted value, printed so that
/// the figure printed is accepted too.
fn up_to_hundredths(v: f64) -> f64 {
    (v * 100.0).ceil() / 100.0
}

fn refusal(setting: &'static str, reason: String) -> Refusal {
    Refusal { setting, reason }
}
