//! Physical units of registers, from the unit each register of the
//! protocol crate's control tables states (`"0.1 V"`, `"degC"`, `"steps/s"`,
//! `"6.5 mA"`, ...): a raw value times the scale is a value in the unit.
//! Positions stay in ticks (the tables' `steps`); registers without a unit
//! (flags, modes, indices, gains) are plain numbers.

use servobus_robot::bus::registers::Register;

/// What Python calls the tables' units.
const NAMES: &[(&str, &str)] = &[
    ("steps", "ticks"),
    ("steps/s", "ticks/s"),
    ("steps/s^2", "ticks/s^2"),
    ("degC", "°C"),
    // A baud-rate index is a number, not a unit.
    ("index", ""),
];

/// The scale and the unit of `reg`'s values: `(0.1, "V")` for a register in
/// tenths of a volt, `(1.0, "ticks")` for a position, `(1.0, "")` for a
/// plain number.
pub(crate) fn physical(reg: &Register) -> (f64, &'static str) {
    let stated = reg.unit.trim();
    let (scale, unit) = match stated.split_once(' ') {
        Some((number, unit)) => match number.parse::<f64>() {
            Ok(scale) if scale.is_finite() && scale > 0.0 => (scale, unit.trim()),
            _ => (1.0, stated),
        },
        None => (1.0, stated),
    };
    let unit = NAMES
        .iter()
        .find(|(table, _)| *table == unit)
        .map_or(unit, |(_, name)| name);
    (scale, unit)
}

#[cfg(test)]
mod tests {
    use super::*;
    use servobus_robot::bus::Series;

    #[test]
    fn units_split_into_scale_and_unit_and_positions_stay_in_ticks() {
        let expected: &[(&str, f64, &str)] = &[
            ("present_voltage", 0.1, "V"),
            ("present_load", 0.1, "%"),
            ("present_current", 6.5, "mA"),
            ("acceleration", 100.0, "ticks/s^2"),
            ("present_position", 1.0, "ticks"),
            ("present_speed", 1.0, "ticks/s"),
            ("present_temperature", 1.0, "°C"),
            ("torque_enable", 1.0, ""),
            ("baud_rate", 1.0, ""),
        ];
        for &(name, scale, unit) in expected {
            let reg = Series::Sts.map().get(name).expect("an STS register");
            assert_eq!(physical(reg), (scale, unit), "{name}");
        }
    }
}
