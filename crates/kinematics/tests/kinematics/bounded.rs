//! A walk or a line asked for more samples than its limit is refused before
//! any sample is made: a tiny period, step or tolerance cannot exhaust
//! memory through the library, whatever its caller checked.

use servobus_kinematics::{
    plan_walk, sample_line, ArmIk, Gait, Held, IkError, Legs, LineOptions, Point3, PoseLine, Walk,
    WalkError, WalkSegment, MAX_WALK_SAMPLES,
};

use crate::robots::{pose, shipped, standing};

/// A tripod walk at 20 mm/s for `seconds`, stepping every `period_s`,
/// sampled every `step_s`.
fn walk(period_s: f64, step_s: f64, seconds: f64) -> Walk {
    Walk {
        gait: Gait::Tripod,
        stride_mm: None,
        lift_mm: 20.0,
        period_s,
        segments: vec![WalkSegment {
            velocity_mm_s: [20.0, 0.0],
            turn_rad_s: 0.0,
            duration_s: seconds,
        }],
        step_s,
    }
}

#[test]
fn a_walk_of_a_billion_steps_is_refused_with_its_count() {
    let s = shipped("hexapod");
    let legs = Legs::new(&s.model).expect("six legs");
    let start = standing(&s);
    // A period of 1 ns over a 1 s walk: a billion swings of each leg.
    match plan_walk(&legs, &walk(1e-9, 0.02, 1.0), &start) {
        Err(WalkError::TooLong { count }) => assert!(count > 1e9, "{count}"),
        other => panic!("{other:?}"),
    }
    // A sampling step of 1 ns: a billion samples.
    let e = plan_walk(&legs, &walk(2.0, 1e-9, 1.0), &start).expect_err("too many samples");
    assert!(
        e.to_string()
            .ends_with(&format!("more than the limit of {MAX_WALK_SAMPLES}")),
        "{e}"
    );
    // Just under the limit in steps, the walk is planned.
    let plan = plan_walk(&legs, &walk(2.0, 0.02, 4.0), &start).expect("walks");
    assert!(plan.samples.len() > 200, "{}", plan.samples.len());
}

#[test]
fn a_walk_with_times_that_are_not_positive_is_refused() {
    let s = shipped("hexapod");
    let legs = Legs::new(&s.model).expect("six legs");
    let start = standing(&s);
    for (period, step, seconds) in [
        (0.0, 0.02, 1.0),
        (-1.0, 0.02, 1.0),
        (f64::NAN, 0.02, 1.0),
        (2.0, 0.0, 1.0),
        (2.0, f64::INFINITY, 1.0),
        (2.0, 0.02, -3.0),
        (2.0, 0.02, f64::NAN),
    ] {
        assert_eq!(
            plan_walk(&legs, &walk(period, step, seconds), &start),
            Err(WalkError::Times),
            "{period} {step} {seconds}"
        );
    }
}

#[test]
fn a_line_stops_at_its_sample_limit() {
    let s = shipped("so101");
    let arm = ArmIk::new(&s.model, "tool").expect("an arm");
    let home = pose(
        &s,
        &[
            ("shoulder_lift", -90.0),
            ("elbow_flex", 90.0),
            ("wrist_flex", 45.0),
        ],
    );
    let previous: Vec<f64> = arm.joints().iter().map(|&j| home[j]).collect();
    let mut chain = vec![0.0; previous.len()];
    let target = servobus_kinematics::ArmTarget {
        xyz: Point3::new(220.0, 60.0, 120.0),
        pitch: Some(60f64.to_radians()),
        roll: None,
    };
    arm.solve(&target, &previous, &mut chain)
        .expect("reachable");
    let from = arm.frame_pose(&chain);
    let mut to = from;
    to.translation.vector.z -= 50.0;
    let line = PoseLine::new(from, to);
    let held = Held {
        pitch: true,
        roll: false,
    };
    let linear = |t: f64| (t / 2.0).clamp(0.0, 1.0);
    let sample =
        |options: &LineOptions| sample_line(&arm, &line, held, &chain, 2.0, linear, options);
    // A coarse first sampling (three samples, 1 s apart) and a fine
    // tolerance: samples are added between them.
    let fine = LineOptions {
        tolerance_mm: 0.01,
        max_step_s: 1.0,
        ..LineOptions::default()
    };
    let free = sample(&fine).expect("the line is followed");
    let n = free.samples.len();
    assert!(n > 3, "{n} samples");
    // The same line allowed one sample fewer than it takes stops there.
    let capped = LineOptions {
        max_samples: n - 1,
        ..fine
    };
    let e = sample(&capped).expect_err("one sample too many");
    assert_eq!(e.reason, IkError::TooManySamples { limit: n - 1 });
    assert!(e.along_mm > 0.0 && e.along_mm <= 50.0, "{e}");
    let exact = LineOptions {
        max_samples: n,
        ..fine
    };
    assert_eq!(sample(&exact).expect("fits exactly").samples.len(), n);
    // A first sampling beyond the limit is refused before it starts: a
    // step of 1 ns over 2 s.
    let dense = LineOptions {
        max_step_s: 1e-9,
        ..LineOptions::default()
    };
    let e = sample(&dense).expect_err("two billion steps");
    assert_eq!(
        e.reason,
        IkError::TooManySamples {
            limit: LineOptions::default().max_samples
        }
    );
    assert_eq!(e.along_mm, 0.0);
}
