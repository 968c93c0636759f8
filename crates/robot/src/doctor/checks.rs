//! The checks of one servo's registers against its joint in the robot file
//! and against the known pitfalls. Pure functions of what was read, so each
//! one is tested without a bus.

use servobus_config::{JointConfig, JointMap};
use servobus_protocol::registers::{self, Register, Series};
use servobus_protocol::StatusFlags;

use super::probe::Ctx;
use super::{Action, Advice, Change, Finding, SetupStep as Step, Severity};

/// Bytes read from each servo: from the firmware version (0) to the status
/// and moving flags (65, 66) and, on STS/SMS, the present current (69, 70).
pub(crate) const fn read_len(series: Series) -> usize {
    match series {
        Series::Sts => 71,
        Series::Scs => 67,
    }
}

/// A servo's memory table from address 0, as one READ returned it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServoState {
    /// Its ID.
    pub id: u8,
    /// The series whose layout the bytes are read with.
    pub series: Series,
    /// The status flags of the reply.
    pub flags: StatusFlags,
    bytes: Vec<u8>,
}

impl ServoState {
    /// The table `bytes` (from address 0) of servo `id`.
    pub fn new(id: u8, series: Series, flags: StatusFlags, bytes: Vec<u8>) -> ServoState {
        ServoState {
            id,
            series,
            flags,
            bytes,
        }
    }

    /// The register called `name`, when the series has it.
    pub fn register(&self, name: &str) -> Option<&'static Register> {
        self.series.map().get(name)
    }

    /// The value of register `name`, when the series has it and it was read.
    pub fn value(&self, name: &str) -> Option<i32> {
        let reg = self.register(name)?;
        let at = usize::from(reg.address);
        let bytes = self.bytes.get(at..at + usize::from(reg.size))?;
        reg.decode(bytes, self.series.byte_order()).ok()
    }

    /// The model number (register 3).
    pub fn model_number(&self) -> u16 {
        self.value("model_number")
            .and_then(|v| u16::try_from(v).ok())
            .unwrap_or(0)
    }

    /// The firmware version, major and minor.
    pub fn firmware(&self) -> (u8, u8) {
        let byte = |a: usize| self.bytes.get(a).copied().unwrap_or(0);
        (byte(0), byte(1))
    }
}

/// The supply a model is rated for, in 0.1 V: (lowest, highest).
///
/// From Feetech's product pages: the STS3215 is sold for 7.4 V (2S) and
/// 12 V (3S) supplies, so its band spans both, 6.0 to 12.6 V; the STS3250
/// is a 12 V servo (9 to 12.6 V); the SM8512BL takes 12 to 24 V (to 25.2 V
/// for a charged 6S pack); the SCS0009 4.8 to 6 V; the SCS15 6 to 8.4 V.
pub fn rated_voltage_dv(model: &str) -> Option<(u8, u8)> {
    Some(match model.to_ascii_uppercase().as_str() {
        "STS3215" => (60, 126),
        "STS3250" => (90, 126),
        "SM8512BL" => (120, 252),
        "SCS0009" => (48, 60),
        "SCS15" => (60, 84),
        _ => return None,
    })
}

/// Joints whose name says they grip (and so stall against what they hold).
pub(crate) fn is_gripper(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    ["grip", "claw", "jaw", "pinch"]
        .iter()
        .any(|w| n.contains(w))
}

/// Protection settings a gripper needs so that holding an object does not
/// cook its motor: the values LeRobot's SO-101 set-up writes (maximum torque
/// 50 %, protection current 250 mA-units, overload torque 25 %).
const GRIPPER_LIMITS: [(&str, i32); 3] = [
    ("max_torque", 500),
    ("protection_current", 250),
    ("overload_torque", 25),
];

/// Status bits that should release the torque (unloading condition, 19):
/// without them a stalled or hot servo keeps pushing until it is damaged.
const MUST_UNLOAD: u8 = StatusFlags::OVERHEAT | StatusFlags::OVERLOAD;

/// Temperature margin below the limit that earns a warning, C.
const WARM_MARGIN_C: i32 = 10;
/// How far a joint may read outside its limits before it counts (rounding
/// of the ticks, a joint resting against its stop): 1 degree, in radians.
const OUTSIDE_TOLERANCE_RAD: f64 = 1.0 * std::f64::consts::PI / 180.0;

impl Ctx<'_> {
    pub(crate) fn finding(
        &self,
        severity: Severity,
        step: Step,
        id: u8,
        register: Option<&'static str>,
    ) -> Finding {
        super::probe::finding(self, severity, step, Some(id), register)
    }

    /// A finding fixed by writing `value` into `register`.
    fn write_fix(
        &self,
        severity: Severity,
        step: Step,
        s: &ServoState,
        name: &str,
        value: i32,
    ) -> Finding {
        let reg = s.register(name);
        let mut f = self.finding(severity, step, s.id, reg.map(|r| r.name));
        f.measured = s.value(name);
        f.advice = Advice::Run(self.target.write_command(
            s.id,
            reg.map_or(name, |r| r.name),
            value,
        ));
        let silent = s.value("status_level") == Some(0);
        f.action = reg.map(|register| Action::Write {
            id: s.id,
            register,
            value,
            silent,
            series: s.series,
        });
        f
    }

    /// Every finding about servo `s`, whose joint in the robot file is
    /// `joint` (none for a servo the file does not name).
    pub(crate) fn servo_findings(
        &self,
        s: &ServoState,
        joint: Option<&JointConfig>,
    ) -> Vec<Finding> {
        let mut out = Vec::new();
        if let Some(joint) = joint {
            if s.model_number() != joint.model.number {
                let found = registers::model_by_number(s.model_number())
                    .map_or_else(|| format!("model #{}", s.model_number()), |m| m.name.into());
                let mut f =
                    self.finding(Severity::Error, Step::Connect, s.id, Some("model_number"));
                f.problem = format!(
                    "servo {} is a {found}, the robot file says {} for joint `{}`",
                    s.id, joint.model.name, joint.name
                );
                f.measured = Some(i32::from(s.model_number()));
                f.advice = Advice::FitModel {
                    model: joint.model.name.to_owned(),
                    edit: self.edit_robot_file(Change::SetModel {
                        joint: joint.name.clone(),
                        model: found.to_ascii_lowercase(),
                    }),
                };
                out.push(f);
                // The other registers mean other things on another model.
                return out;
            }
        }
        self.reply_settings(s, &mut out);
        self.lock(s, &mut out);
        self.health(s, joint, &mut out);
        if let Some(joint) = joint {
            self.wanted_settings(s, joint, &mut out);
            // A wheel has no position to keep within limits.
            if !joint.is_wheel() {
                self.limits(s, joint, &mut out);
            }
            self.protection(s, joint, &mut out);
            self.calibration(s, joint, &mut out);
        }
        out
    }

    fn reply_settings(&self, s: &ServoState, out: &mut Vec<Finding>) {
        if let Some(delay) = s.value("return_delay").filter(|&d| d != 0) {
            let us = 2 * delay;
            let expected = self.bus.return_delay.as_micros();
            let severity = if u128::from(us.unsigned_abs()) > expected {
                Severity::Error
            } else {
                Severity::Warning
            };
            let mut f = self.write_fix(severity, Step::Configure, s, "return_delay", 0);
            f.problem = format!(
                "return delay is {us} us (the robot file expects {expected} us): every reply \
                 waits that long{}",
                if severity == Severity::Error {
                    ", past the deadlines the runtime derives"
                } else {
                    ""
                }
            );
            out.push(f);
        }
        // STS level 1 and SCS level 2 answer every instruction, which is what
        // the driver expects by default.
        let full = match s.series {
            Series::Sts => 1,
            Series::Scs => 2,
        };
        if let Some(level) = s.value("status_level").filter(|&l| l < full) {
            let mut f = self.write_fix(Severity::Warning, Step::Configure, s, "status_level", full);
            f.problem = format!(
                "status return level is {level}: the servo does not answer WRITE, so a write \
                 cannot be confirmed (the driver expects level {full})"
            );
            out.push(f);
        }
    }

    fn lock(&self, s: &ServoState, out: &mut Vec<Finding>) {
        if s.value("lock") == Some(0) {
            // Every EEPROM write of servobus closes the lock again, holding
            // signals until it has: one left open is a write cut short by
            // power loss or SIGKILL, or another program's. Motion refuses it.
            let mut f = self.write_fix(Severity::Error, Step::Configure, s, "lock", 1);
            f.problem = "EEPROM lock left open: a write of its settings was cut short (power \
                         loss, a killed program) or another program left it open, so they may \
                         be half-written (see the limits and offsets here); any write to a \
                         setting persists, stray ones included, and motion refuses the servo"
                .into();
            out.push(f);
        }
    }

    fn health(&self, s: &ServoState, joint: Option<&JointConfig>, out: &mut Vec<Finding>) {
        let torque_off = self.target.write_command(s.id, "torque_enable", 0);
        if let (Some(t), Some(limit)) = (s.value("present_temperature"), s.value("max_temperature"))
        {
            let hot = s.flags.contains(StatusFlags::OVERHEAT) || t >= limit;
            if hot || t >= limit - WARM_MARGIN_C {
                let sev = if hot {
                    Severity::Error
                } else {
                    Severity::Warning
                };
                let mut f = self.finding(sev, Step::Check, s.id, Some("present_temperature"));
                f.problem = format!(
                    "temperature {t} C, limit {limit} C{}",
                    if hot { " (overheat)" } else { "" }
                );
                f.measured = Some(t);
                f.advice = Advice::Cool(torque_off);
                out.push(f);
            }
        }
        let Some(v) = s.value("present_voltage") else {
            return;
        };
        let volts = |dv: i32| f64::from(dv) / 10.0;
        let lo = s.value("min_voltage").unwrap_or(0);
        let hi = s.value("max_voltage").unwrap_or(255);
        let load = s.value("present_load").map_or(0, i32::abs);
        let when = if load >= 200 {
            format!("under {} % load", load / 10)
        } else {
            "at rest".to_string()
        };
        let rated = joint.and_then(|j| rated_voltage_dv(j.model.name));
        let model = joint.map_or("servo", |j| j.model.name);
        if s.flags.contains(StatusFlags::VOLTAGE) || v < lo || v > hi {
            let mut f = self.finding(Severity::Error, Step::Check, s.id, Some("present_voltage"));
            f.problem = format!(
                "supply {:.1} V {when} is outside the servo's limits {:.1}..{:.1} V (voltage flag)",
                volts(v),
                volts(lo),
                volts(hi)
            );
            f.measured = Some(v);
            f.advice = supply_fix(model, rated);
            out.push(f);
        } else if let Some((rlo, rhi)) =
            rated.filter(|&(a, b)| v < i32::from(a) || v > i32::from(b))
        {
            let register = Some("present_voltage");
            let mut f = self.finding(Severity::Warning, Step::Check, s.id, register);
            f.problem = format!(
                "supply {:.1} V {when} is outside the {model}'s rating {:.1}..{:.1} V",
                volts(v),
                volts(i32::from(rlo)),
                volts(i32::from(rhi))
            );
            f.measured = Some(v);
            f.advice = supply_fix(model, rated);
            out.push(f);
        }
    }

    fn limits(&self, s: &ServoState, joint: &JointConfig, out: &mut Vec<Finding>) {
        let map = JointMap::new(joint, self.robot.units);
        let units = self.robot.units;
        let a = map.to_ticks(units.to_rad(joint.min));
        let b = map.to_ticks(units.to_rad(joint.max));
        let (lo, hi) = (a.min(b), a.max(b));
        if let (Some(min), Some(max)) = (s.value("min_angle_limit"), s.value("max_angle_limit")) {
            // 0 and 0 switch the limits off (multi-turn or wheel modes).
            if (min, max) != (0, 0) {
                for (name, reg, want, narrow) in [
                    ("min_angle_limit", min, lo, min > lo),
                    ("max_angle_limit", max, hi, max < hi),
                ] {
                    if narrow {
                        let mut f = self.write_fix(Severity::Error, Step::Configure, s, name, want);
                        f.problem = format!(
                            "{name} is {reg} ticks, narrower than joint `{}`'s limits \
                             ({} ticks): the servo stops short of goals the runtime sends",
                            joint.name, want
                        );
                        out.push(f);
                    }
                }
            }
        }
        // Without a calibration a real joint's angle means nothing yet: the
        // advice is to calibrate (see `uncalibrated`), not to move it.
        if let (Some(pos), false) = (s.value("present_position"), self.uncalibrated()) {
            let rad = map.from_ticks(super::calibration::play_frame_tick(s, joint, pos));
            let (min, max) = (units.to_rad(joint.min), units.to_rad(joint.max));
            if rad < min - OUTSIDE_TOLERANCE_RAD || rad > max + OUTSIDE_TOLERANCE_RAD {
                let mut f =
                    self.finding(Severity::Error, Step::Check, s.id, Some("present_position"));
                f.problem = format!(
                    "joint `{}` is at {:.1} {units} ({pos} ticks), outside its limits {}..{} {units}",
                    joint.name,
                    units.from_rad(rad),
                    joint.min,
                    joint.max
                );
                f.measured = Some(pos);
                f.advice =
                    Advice::MoveIntoLimits(self.target.write_command(s.id, "torque_enable", 0));
                out.push(f);
            }
        }
    }

    fn protection(&self, s: &ServoState, joint: &JointConfig, out: &mut Vec<Finding>) {
        let gripper = is_gripper(&joint.name);
        if let Some(mask) = s.value("unloading_condition") {
            let mask = u8::try_from(mask).unwrap_or(0);
            if mask & MUST_UNLOAD != MUST_UNLOAD {
                let sev = if gripper {
                    Severity::Error
                } else {
                    Severity::Warning
                };
                let mut f = self.write_fix(
                    sev,
                    Step::Configure,
                    s,
                    "unloading_condition",
                    i32::from(mask | MUST_UNLOAD),
                );
                f.problem = format!(
                    "unloading condition {mask:#04x} lacks overheat or overload: a stalled \
                     servo keeps its torque until it is damaged"
                );
                out.push(f);
            }
        }
        if !gripper {
            return;
        }
        // A register the joint's `servo:` settings set is the robot file's
        // to choose (see `wanted_settings`).
        let set_by_file = |name: &str| joint.servo_writes().iter().any(|w| w.register.name == name);
        for (name, most) in GRIPPER_LIMITS {
            if set_by_file(name) {
                continue;
            }
            if let Some(v) = s.value(name).filter(|&v| v > most) {
                let mut f = self.write_fix(Severity::Warning, Step::Configure, s, name, most);
                f.problem = format!(
                    "gripper `{}`: {name} is {v} (at most {most} keeps a gripper that holds an \
                     object from overheating)",
                    joint.name
                );
                out.push(f);
            }
        }
    }
}

fn supply_fix(model: &str, rated: Option<(u8, u8)>) -> Advice {
    Advice::Supply {
        model: model.to_owned(),
        rated,
    }
}
