//! The checks of what the robot file asks of a servo's EEPROM: the
//! operating mode of its joint (`mode:`) and the EEPROM registers of its
//! `servo:` settings. A run writes neither (EEPROM writes persist, so they
//! are made only when asked), so each difference is a finding fixed by an
//! EEPROM write that `--write-servos` asks for ([`Action::Store`]).
//!
//! | robot file             | register               | wanted                      |
//! |------------------------|------------------------|-----------------------------|
//! | `mode: position`       | `mode` (33)            | 0                           |
//! | `mode: wheel`          | `mode` (33)            | 1 (constant speed)          |
//! | `servo: {p, d, i}`     | `p/d/i_coefficient`    | the file's value            |
//! | `protection_current`   | `protection_current`   | the file's mA in 6.5 mA     |
//! | `max_temperature`      | `max_temperature`      | the file's degC             |
//!
//! The RAM settings (`torque_limit`, `acceleration`) are not checked: the
//! run writes them at every start and the servo forgets them at power-off.

use serde::Serialize;
use servobus_config::{JointConfig, JointMode, ServoWrite};
use servobus_protocol::registers::Register;

use super::checks::ServoState;
use super::probe::Ctx;
use super::{Action, Advice, Finding, SetupStep as Step, Severity};

/// A register whose value the robot file asks for and the servo does not
/// hold: a joint's operating mode, or an EEPROM `servo:` setting.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SettingMismatch {
    /// The joint.
    pub joint: String,
    /// What the robot file calls it: `mode`, or the `servo:` key (`p`,
    /// `protection_current`, ...).
    pub setting: &'static str,
    /// The register's name.
    pub register: &'static str,
    /// The register's address.
    pub address: u8,
    /// The value the servo holds, in the register's units.
    pub found: i32,
    /// The value the robot file asks for, in the register's units.
    pub wanted: i32,
    /// `found` in the robot file's terms (`position`, `3250 mA`), when
    /// the register counts in anything but plain numbers.
    pub found_as: Option<String>,
    /// `wanted` in the robot file's terms.
    pub wanted_as: Option<String>,
}

/// The operating mode (register `mode`) a joint's servo needs.
fn operating_mode(mode: JointMode) -> i32 {
    i32::from(mode.operating_mode())
}

/// What operating mode `value` does, as the robot file says it.
fn mode_name(value: i32) -> &'static str {
    match value {
        0 => "position",
        1 => "wheel",
        2 => "PWM",
        3 => "step",
        _ => "unknown",
    }
}

/// `value` of `reg` in the unit the register states (`6.5 mA`: 231 is
/// `1501.5 mA`); `None` for a plain number.
fn in_units(reg: &Register, value: i32) -> Option<String> {
    let stated = reg.unit.trim();
    if stated.is_empty() {
        return None;
    }
    let (step, unit) = match stated.split_once(' ') {
        Some((step, unit)) => match step.parse::<f64>() {
            Ok(step) => (step, unit.trim()),
            Err(_) => (1.0, stated),
        },
        None => (1.0, stated),
    };
    // Hundredths: a step such as 6.5 or 0.1 makes no longer figure.
    let v = (f64::from(value) * step * 100.0).round() / 100.0;
    Some(format!("{v} {unit}"))
}

impl Ctx<'_> {
    /// What joint `joint` asks of servo `s`'s EEPROM that it does not hold:
    /// its operating mode, then its EEPROM `servo:` settings.
    pub(crate) fn wanted_settings(
        &self,
        s: &ServoState,
        joint: &JointConfig,
        out: &mut Vec<Finding>,
    ) {
        let wanted = operating_mode(joint.mode);
        if let (Some(reg), Some(found)) = (s.register("mode"), s.value("mode")) {
            if found != wanted {
                out.push(self.mode_finding(s, joint, reg, found, wanted));
            }
        }
        for w in joint.servo_writes().iter().filter(|w| w.eeprom) {
            let want = w.register.from_raw(w.raw);
            match s.value(w.register.name) {
                Some(found) if found != want => {
                    out.push(self.setting_finding(s, joint, w, found, want));
                }
                _ => {}
            }
        }
    }

    /// Servo `s` is in operating mode `found` where joint `joint` needs
    /// `wanted`: the run refuses it.
    fn mode_finding(
        &self,
        s: &ServoState,
        joint: &JointConfig,
        reg: &'static Register,
        found: i32,
        wanted: i32,
    ) -> Finding {
        let mut f = self.finding(Severity::Error, Step::Configure, s.id, Some(reg.name));
        let kind = if joint.is_wheel() {
            "a wheel (`mode: wheel`)"
        } else {
            "a position joint"
        };
        f.problem = format!(
            "operating mode is {found} ({}), joint `{}` is {kind} and needs mode {wanted} ({}): \
             a run refuses the servo",
            mode_name(found),
            joint.name,
            mode_name(wanted)
        );
        f.measured = Some(found);
        // The doctor turns the torque off before it changes the mode, which
        // a bare write would not.
        let fix = super::probe::fix_all_command(self.target, self.robot, true);
        f.advice = Advice::Run(fix);
        f.action = Some(self.store(s, reg, wanted, true));
        f.setting = Some(SettingMismatch {
            joint: joint.name.clone(),
            setting: "mode",
            register: reg.name,
            address: reg.address,
            found,
            wanted,
            found_as: Some(mode_name(found).to_owned()),
            wanted_as: Some(mode_name(wanted).to_owned()),
        });
        f
    }

    /// Servo `s` holds `found` in the register of joint `joint`'s `servo:`
    /// setting `w`, which asks for `wanted`.
    fn setting_finding(
        &self,
        s: &ServoState,
        joint: &JointConfig,
        w: &ServoWrite,
        found: i32,
        wanted: i32,
    ) -> Finding {
        let reg = w.register;
        let mut f = self.finding(Severity::Warning, Step::Configure, s.id, Some(reg.name));
        let (found_as, wanted_as) = (in_units(reg, found), in_units(reg, wanted));
        let shown = |raw: i32, units: &Option<String>| match units {
            Some(u) => format!("{u} ({raw})"),
            None => raw.to_string(),
        };
        f.problem = format!(
            "{} (register {}) is {}, joint `{}`'s `servo: {}` asks for {}: a run does not write \
             EEPROM, so the servo keeps its own",
            reg.name,
            reg.address,
            shown(found, &found_as),
            joint.name,
            w.setting,
            shown(wanted, &wanted_as)
        );
        f.measured = Some(found);
        f.advice = Advice::Run(self.target.write_command(s.id, reg.name, wanted));
        f.action = Some(self.store(s, reg, wanted, false));
        f.setting = Some(SettingMismatch {
            joint: joint.name.clone(),
            setting: w.setting,
            register: reg.name,
            address: reg.address,
            found,
            wanted,
            found_as,
            wanted_as,
        });
        f
    }

    /// The EEPROM write of `value` into `reg` of servo `s`, the torque off
    /// first when `torque_off`.
    fn store(
        &self,
        s: &ServoState,
        reg: &'static Register,
        value: i32,
        torque_off: bool,
    ) -> Action {
        Action::Store {
            id: s.id,
            register: reg,
            value,
            silent: s.value("status_level") == Some(0),
            series: s.series,
            torque_off,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use servobus_protocol::registers::Series;

    fn reg(name: &str) -> &'static Register {
        Series::Sts.map().get(name).expect("an STS register")
    }

    #[test]
    fn values_are_shown_in_the_unit_the_register_states() {
        assert_eq!(
            in_units(reg("protection_current"), 500).as_deref(),
            Some("3250 mA")
        );
        assert_eq!(
            in_units(reg("protection_current"), 231).as_deref(),
            Some("1501.5 mA")
        );
        assert_eq!(
            in_units(reg("max_temperature"), 70).as_deref(),
            Some("70 degC")
        );
        assert_eq!(
            in_units(reg("torque_limit"), 601).as_deref(),
            Some("60.1 %")
        );
        assert_eq!(in_units(reg("p_coefficient"), 32), None);
    }

    #[test]
    fn a_wheel_needs_mode_1_and_a_position_joint_mode_0() {
        assert_eq!(operating_mode(JointMode::Wheel), 1);
        assert_eq!(operating_mode(JointMode::Position), 0);
        assert_eq!(mode_name(1), "wheel");
        assert_eq!(mode_name(0), "position");
        assert_eq!(mode_name(7), "unknown");
    }
}
