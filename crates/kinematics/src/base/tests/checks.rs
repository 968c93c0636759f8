//! The checks of a `base:` section and of what a base is asked to do: every
//! error names its field and says what is accepted.

use super::*;

#[test]
fn the_geometry_errors_name_the_field() {
    let lekiwi_with = |from: &str, to: &str| refused(&LEKIWI.replace(from, to));
    assert_eq!(
        lekiwi_with("wheel_back", "x"),
        r#"base.omni3.wheels[1].joint: no joint called "x""#
    );
    assert_eq!(
        lekiwi_with("50.8", "-3"),
        "base.omni3.wheel_radius_mm: must be a finite number > 0, not -3"
    );
    assert!(lekiwi_with("125", "0").starts_with("base.omni3.base_radius_mm: must be"));
    assert!(lekiwi_with("125", ".inf").ends_with("not inf"));
    assert_eq!(
        lekiwi_with("angle_deg: 270", "angle_deg: .nan"),
        "base.omni3.wheels[1].angle_deg: must be a finite number, not NaN"
    );
    assert_eq!(
        lekiwi_with("wheel_right", "wheel_left"),
        "base.omni3.wheels[2].joint: joint \"wheel_left\" already drives \
         base.omni3.wheels[0].joint (each wheel needs its own joint)"
    );
    assert_eq!(
        lekiwi_with("    - {joint: wheel_right, angle_deg: 30}\n", ""),
        "base.omni3.wheels: an omni3 base has exactly 3 wheels, not 2"
    );
    let four = format!("{LEKIWI}    - {{joint: wheel_l, angle_deg: 90}}\n");
    assert!(matches!(
        check(&four),
        Err(BaseError::WheelCount { count: 4 })
    ));
    let diff_with = |from: &str, to: &str| refused(&DIFF.replace(from, to));
    assert_eq!(
        diff_with("right: wheel_r", "right: wheel_l"),
        "base.differential.right: joint \"wheel_l\" already drives base.differential.left \
         (each wheel needs its own joint)"
    );
    assert!(diff_with("track_mm: 160", "track_mm: .nan").starts_with("base.differential.track_mm:"));
    assert!(diff_with("50", "-1").starts_with("base.differential.wheel_radius_mm:"));
    assert!(diff_with("wheel_l,", "nope,").starts_with("base.differential.left: no joint"));
}

#[test]
fn omni_wheels_must_sit_at_three_angles() {
    let e = omni([90.0, 90.0, 90.0], 50.0, 100.0).expect_err("one angle");
    assert!(
        e.to_string().contains("all three wheels sit at 90 deg"),
        "{e}"
    );
    // 390 is 30 around the circle.
    let e = omni([30.0, 150.0, 390.0], 50.0, 100.0).expect_err("two at one angle");
    assert!(
        matches!(
            e,
            BaseError::CloseWheels {
                first: 0,
                second: 2,
                ..
            }
        ),
        "{e:?}"
    );
    assert!(
        e.to_string()
            .contains("wheels[0] (30 deg) and wheels[2] (390 deg)"),
        "{e}"
    );
    assert!(omni([0.0, 0.5, 180.0], 50.0, 100.0).is_err());
    assert!(
        omni([359.5, 0.2, 180.0], 50.0, 100.0).is_err(),
        "close across 0"
    );
    assert!(omni([0.0, 1.5, 180.0], 50.0, 100.0).is_ok());
    // Radii far from any robot's leave nothing to invert.
    assert_eq!(
        omni([30.0, 150.0, 270.0], 1e300, 1e-300),
        Err(BaseError::Singular)
    );
}

#[test]
fn the_velocity_errors_say_what_is_wrong() {
    let (b, d) = (lekiwi(), diff());
    let mut two = [0.0; 2];
    let e = d
        .wheel_speeds(&twist(0.2, 0.1, 0.0), &mut two)
        .expect_err("sideways");
    assert!(
        e.to_string()
            .contains("a differential base cannot move sideways"),
        "{e}"
    );
    assert!(
        d.wheel_speeds(&twist(0.2, 1e-10, 0.0), &mut two).is_ok(),
        "rounding is not sideways"
    );
    let e = b
        .wheel_speeds(&twist(0.0, 0.0, f64::NAN), &mut [0.0; 3])
        .expect_err("NaN");
    assert_eq!(
        e.to_string(),
        "base.theta: must be a finite number, not NaN"
    );
    let e = b
        .wheel_speeds(&twist(0.1, 0.0, 0.0), &mut two)
        .expect_err("two outputs");
    assert!(matches!(
        e,
        BaseError::WheelSlice {
            what: "output",
            expected: 3,
            actual: 2
        }
    ));
    let e = b
        .wheel_speeds(&twist(1e308, 0.0, 0.0), &mut [0.0; 3])
        .expect_err("too fast");
    assert_eq!(e, BaseError::Overflow);
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = b
            .limited(&twist(0.1, 0.0, 0.0), &[1.0, bad, 1.0], &mut [0.0; 3])
            .expect_err("limit");
        assert!(
            e.to_string()
                .starts_with("speed limit of wheel joint \"wheel_back\""),
            "{e}"
        );
    }
    let e = b
        .limited(&twist(0.1, 0.0, 0.0), &[1.0; 2], &mut [0.0; 3])
        .expect_err("two limits");
    assert!(matches!(
        e,
        BaseError::WheelSlice {
            what: "wheel limits",
            ..
        }
    ));
    let e = d
        .twist(&[1.0, f64::NEG_INFINITY])
        .expect_err("a bad reading");
    assert!(
        e.to_string()
            .starts_with("measured speed of wheel joint \"wheel_r\""),
        "{e}"
    );
    assert!(matches!(
        d.twist(&[1.0; 3]),
        Err(BaseError::WheelSlice {
            what: "wheel speeds",
            ..
        })
    ));
}

#[test]
fn the_section_reads_from_yaml() {
    let spec = parse(&format!("{DIFF}\n"));
    let want = DifferentialSpec {
        wheel_radius_mm: 50.0,
        track_mm: 160.0,
        left: "wheel_l".into(),
        right: "wheel_r".into(),
    };
    assert_eq!(spec, BaseSpec::Differential(want));
    let BaseSpec::Omni3(omni) = parse(LEKIWI) else {
        panic!("LeKiwi's base is omni3");
    };
    assert_eq!((omni.wheels.len(), omni.wheels[2].angle_deg), (3, 30.0));
    let wrong = |yaml: &str| {
        serde_yaml::from_str::<BaseSpec>(yaml)
            .expect_err("a section the test made wrong")
            .to_string()
    };
    let e = wrong(&LEKIWI.replace("base_radius_mm", "radius_mm"));
    assert!(e.contains("unknown field `radius_mm`"), "{e}");
    let e = wrong(&DIFF.replace("left:", "lft:"));
    assert!(e.contains("unknown field `lft`"), "{e}");
    let e = wrong("mecanum: {wheel_radius_mm: 40}");
    assert!(
        e.contains("unknown field `mecanum`, expected `omni3` or `differential`"),
        "{e}"
    );
    let e = wrong(&format!("{LEKIWI}{DIFF}"));
    assert!(e.contains("not both"), "{e}");
    let e = wrong("{}");
    assert!(e.contains("a base needs its kind"), "{e}");
    let e = wrong("3");
    assert!(e.contains("a base: a mapping with one key"), "{e}");
    let e = wrong("omni3: [1, 2]");
    assert!(e.contains("an omni3 base: a mapping with"), "{e}");
}
