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
            format!(
                "{}: needs a peak {quantity} of {:.4} {unit}, above the limit {:.4} {unit}",
                name(joint),
                units.from_rad(peak),
                units.from_rad(limit)
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
            "joint `femur`: needs a peak velocity of 180.0000 deg/s, above the limit 90.0000 \
             deg/s"
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
}
