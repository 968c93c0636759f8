//! The planner's errors in a file's terms: joints by name, angles in the
//! file's units. The planner counts joints from 0 and works in radians; a
//! user wrote names and degrees.

use servobus_trajectory::{PlanError, Quantity};

use super::limits::Rounded;
use super::Units;

/// The unit of a quantity of an angle in `units`.
pub(crate) fn quantity_unit(units: Units, q: Quantity) -> String {
    match q {
        Quantity::Position => units.name().to_owned(),
        Quantity::Velocity => format!("{units}/s"),
        Quantity::Acceleration => format!("{units}/s^2"),
        Quantity::Jerk => format!("{units}/s^3"),
        _ => units.name().to_owned(),
    }
}

/// A peak and the limit it is above, as a message says them: to 0.1, as
/// the planner's other messages say lengths, angles and limits, whatever
/// the quantity (a jerk of thousands of deg/s^3 as well as a position);
/// with more decimals (at most 4) only when 0.1 would print the two alike.
pub(crate) fn peak_and_limit(peak: f64, limit: f64) -> (String, String) {
    let mut decimals = 1;
    while decimals < 4 && format!("{peak:.decimals$}") == format!("{limit:.decimals$}") {
        decimals += 1;
    }
    (format!("{peak:.decimals$}"), format!("{limit:.decimals$}"))
}

/// The keyframe (or sample) `e` is about, when it is about one.
pub(crate) fn keyframe_of(e: &PlanError) -> Option<usize> {
    match *e {
        PlanError::WrongJointCount { keyframe, .. }
        | PlanError::NotFinite { keyframe, .. }
        | PlanError::OutOfRange { keyframe, .. }
        | PlanError::TimeNotIncreasing { keyframe, .. }
        | PlanError::LimitExceeded { keyframe, .. }
        | PlanError::TooSoon { keyframe, .. } => Some(keyframe),
        _ => None,
    }
}

/// What `e` says, without its keyframe, with joint `j` named `joints[j]`
/// and every angle in `units` (the planner's are radians).
pub(crate) fn plan_reason(e: &PlanError, joints: &[String], units: Units) -> String {
    let name = |j: usize| match joints.get(j) {
        Some(n) => format!("joint `{n}`"),
        None => format!("joint {j}"),
    };
    let angle = |rad: f64| Rounded(units.from_rad(rad));
    match *e {
        PlanError::LimitExceeded {
            joint,
            quantity,
            peak,
            limit,
            ..
        } => {
            let unit = quantity_unit(units, quantity);
            let (peak, limit) = peak_and_limit(units.from_rad(peak), units.from_rad(limit));
            format!(
                "{}: needs a peak {quantity} of {peak} {unit}, above the limit {limit} {unit}",
                name(joint),
            )
        }
        PlanError::OutOfRange {
            joint,
            position,
            min,
            max,
            ..
        } => format!(
            "{}: {} {units} is outside its limits [{}, {}] {units}",
            name(joint),
            angle(position),
            angle(min),
            angle(max)
        ),
        PlanError::NotFinite { joint, .. } => format!("{}: a value is not finite", name(joint)),
        PlanError::InvalidLimits { joint, reason } => {
            format!("{}: invalid limits: {reason}", name(joint))
        }
        PlanError::TooSoon {
            needed, available, ..
        } => format!("needs {needed:.3} s to reach but only {available:.3} s are left"),
        PlanError::TimeNotIncreasing { at, previous, .. } => {
            format!("{at:.3} s is not after the time before it, {previous:.3} s")
        }
        _ => e.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joints_are_named_and_angles_in_the_files_units() {
        let joints = vec!["coxa".to_owned(), "femur".to_owned()];
        let e = PlanError::LimitExceeded {
            keyframe: 37,
            joint: 1,
            quantity: Quantity::Velocity,
            peak: std::f64::consts::PI,
            limit: std::f64::consts::FRAC_PI_2,
        };
        assert_eq!(keyframe_of(&e), Some(37));
        assert_eq!(
            plan_reason(&e, &joints, Units::Deg),
            "joint `femur`: needs a peak velocity of 180.0 deg/s, above the limit 90.0 deg/s"
        );
        let e = PlanError::OutOfRange {
            keyframe: 2,
            joint: 0,
            position: std::f64::consts::PI,
            min: -std::f64::consts::FRAC_PI_2,
            max: std::f64::consts::FRAC_PI_2,
        };
        assert_eq!(
            plan_reason(&e, &joints, Units::Deg),
            "joint `coxa`: 180 deg is outside its limits [-90, 90] deg"
        );
        let text = plan_reason(&e, &joints, Units::Rad);
        assert!(text.ends_with("[-1.57079633, 1.57079633] rad"), "{text}");
        // A joint index with no name is still said.
        let e = PlanError::NotFinite {
            keyframe: 0,
            joint: 5,
        };
        assert_eq!(
            plan_reason(&e, &joints, Units::Deg),
            "joint 5: a value is not finite"
        );
    }

    #[test]
    fn a_jerk_is_said_to_the_same_decimals_as_the_other_limits() {
        let joints = vec!["tibia".to_owned()];
        let e = PlanError::LimitExceeded {
            keyframe: 3,
            joint: 0,
            quantity: Quantity::Jerk,
            peak: 12_345.678_9_f64.to_radians(),
            limit: 10_000.0_f64.to_radians(),
        };
        assert_eq!(
            plan_reason(&e, &joints, Units::Deg),
            "joint `tibia`: needs a peak jerk of 12345.7 deg/s^3, above the limit 10000.0 deg/s^3"
        );
    }

    #[test]
    fn a_peak_just_above_its_limit_gets_the_decimals_that_tell_them_apart() {
        assert_eq!(peak_and_limit(180.0, 90.0), ("180.0".into(), "90.0".into()));
        assert_eq!(
            peak_and_limit(90.03, 90.0),
            ("90.03".into(), "90.00".into())
        );
        assert_eq!(
            peak_and_limit(0.4237, 0.4236),
            ("0.4237".into(), "0.4236".into())
        );
        // Four at most, even when they still print alike.
        assert_eq!(
            peak_and_limit(1.000_01, 1.0),
            ("1.0000".into(), "1.0000".into())
        );
    }
}
