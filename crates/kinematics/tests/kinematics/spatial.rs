//! Tool lines, body moves and walks on the shipped robots' geometry.

use servobus_kinematics::{
    plan_walk, sample_line, ArmIk, Gait, Held, IkError, Legs, LineOptions, Point3, PoseLine, Poses,
    Walk, WalkError, WalkSegment,
};

use crate::robots::{pose, shipped, standing, Shipped};

fn linear(d: f64) -> impl Fn(f64) -> f64 {
    move |t| (t / d).clamp(0.0, 1.0)
}

/// The SO-101 with its tool at (220, 60, 120) pitched down 60 deg.
fn arm_above_table(s: &Shipped, arm: &ArmIk) -> Vec<f64> {
    arm_at(s, arm, [220.0, 60.0, 120.0], 60.0)
}

/// The SO-101 with its tool at `xyz` pitched down `pitch` deg.
fn arm_at(s: &Shipped, arm: &ArmIk, xyz: [f64; 3], pitch: f64) -> Vec<f64> {
    let target = servobus_kinematics::ArmTarget {
        xyz: Point3::from(xyz),
        pitch: Some(pitch.to_radians()),
        roll: None,
    };
    let home = pose(
        s,
        &[
            ("shoulder_lift", -90.0),
            ("elbow_flex", 90.0),
            ("wrist_flex", 45.0),
        ],
    );
    let previous: Vec<f64> = arm.joints().iter().map(|&j| home[j]).collect();
    let mut out = vec![0.0; previous.len()];
    arm.solve(&target, &previous, &mut out).expect("reachable");
    out
}

#[test]
fn a_line_keeps_joint_steps_within_the_tolerance_of_the_line() {
    let s = shipped("so101");
    let arm = ArmIk::new(&s.model, "tool").expect("an arm");
    let chain = arm_above_table(&s, &arm);
    let from = arm.frame_pose(&chain);
    let mut to = from;
    to.translation.vector.z -= 50.0;
    let line = PoseLine::new(from, to);
    let options = LineOptions::default();
    let held = Held {
        pitch: true,
        roll: false,
    };
    let plan = sample_line(&arm, &line, held, &chain, 2.0, linear(2.0), &options)
        .expect("a line the arm can follow");
    assert!(plan.samples.len() >= 41, "{} samples", plan.samples.len());
    // Every sample on the line, and the joints' midpoints within the
    // tolerance.
    for w in plan.samples.windows(2) {
        for (q, f) in [(&w[0].q, 0.0), (&w[1].q, 0.0)] {
            let p = arm.frame_pose(q).translation.vector;
            assert!(line.distance_mm(&p.into()) < 1e-3 + f);
        }
        let mid: Vec<f64> = w[0]
            .q
            .iter()
            .zip(&w[1].q)
            .map(|(a, b)| 0.5 * (a + b))
            .collect();
        let p = arm.frame_pose(&mid).translation.vector;
        assert!(line.distance_mm(&p.into()) <= options.tolerance_mm);
    }
    let end = plan.samples.last().expect("samples");
    let p = arm.frame_pose(&end.q).translation.vector;
    assert!((p - to.translation.vector).norm() < 0.01);
    assert!(plan.min_dexterity > options.min_dexterity);
}

#[test]
fn a_line_to_the_arm_stretched_straight_is_refused_as_near_a_singularity() {
    let s = shipped("so101");
    let arm = ArmIk::new(&s.model, "tool").expect("an arm");
    // At the shoulder_lift axis's height (64.8 + 54.2), moving straight
    // out to 440.73 mm. The tool sits 7.9 below the roll axis, 159.23
    // beyond the wrist flex axis: pitched up atan(7.9 / 159.23) = 2.84 deg,
    // that 159.43 runs level, in line with the upper arm (116.0) and the
    // forearm (135.0) stretched straight. The lift axis is at x = 30.4 and
    // the arm reaches 410.43 from it, so the end is 0.1 mm short of the
    // arm stretched straight.
    let chain = arm_at(&s, &arm, [250.0, 0.0, 119.0], -2.84);
    let from = arm.frame_pose(&chain);
    let mut to = from;
    to.translation.vector.x = 440.73;
    let line = PoseLine::new(from, to);
    let held = Held {
        pitch: true,
        roll: false,
    };
    let err = sample_line(
        &arm,
        &line,
        held,
        &chain,
        4.0,
        linear(4.0),
        &LineOptions::default(),
    )
    .expect_err("to the stretched arm");
    assert!(matches!(err.reason, IkError::Singular { .. }), "{err}");
    // Refused near the end of the 190.73 mm line, not at its start.
    assert!(err.along_mm > 150.0 && err.along_mm <= 190.73, "{err}");
}

#[test]
fn a_line_out_of_reach_is_refused_with_the_distance_short() {
    let s = shipped("so101");
    let arm = ArmIk::new(&s.model, "tool").expect("an arm");
    let chain = arm_above_table(&s, &arm);
    let from = arm.frame_pose(&chain);
    let mut to = from;
    to.translation.vector.x = 600.0;
    let line = PoseLine::new(from, to);
    let err = sample_line(
        &arm,
        &line,
        Held::default(),
        &chain,
        4.0,
        linear(4.0),
        &LineOptions::default(),
    )
    .expect_err("out of reach");
    assert!(matches!(err.reason, IkError::Unreachable { .. }), "{err}");
}

fn forward(velocity: f64, seconds: f64) -> Walk {
    Walk {
        gait: Gait::Ripple,
        stride_mm: Some(60.0),
        lift_mm: 20.0,
        period_s: 2.0,
        segments: vec![WalkSegment {
            velocity_mm_s: [velocity, 0.0],
            turn_rad_s: 0.0,
            duration_s: seconds,
        }],
        step_s: 0.02,
    }
}

#[test]
fn a_walk_covers_its_distance_and_ends_standing_where_it_started_on_the_body() {
    let s = shipped("hexapod");
    let legs = Legs::new(&s.model).expect("six legs");
    let start = standing(&s);
    // 40 mm/s for 5 s: 200 mm.
    let plan = plan_walk(&legs, &forward(40.0, 5.0), &start).expect("walks");
    assert!((plan.end[0] - 200.0).abs() < 0.5, "{:?}", plan.end);
    assert!(plan.end[1].abs() < 1e-6 && plan.end[2].abs() < 1e-9);
    assert!((plan.distance_mm - 200.0).abs() < 0.5);
    // A ripple keeps four feet down: the body well inside them.
    assert!(plan.min_margin_mm > 10.0, "{}", plan.min_margin_mm);
    assert!(plan.low_margins.is_empty());
    let last = &plan.samples.last().expect("samples").q;
    let mut poses = Poses::new(&s.model);
    let (mut a, mut b) = (vec![Point3::origin(); 6], vec![Point3::origin(); 6]);
    legs.feet(&start, &mut poses, &mut a);
    legs.feet(last, &mut poses, &mut b);
    for (p, q) in a.iter().zip(&b) {
        assert!((p - q).norm() < 0.5, "{p} vs {q}");
    }
}

#[test]
fn a_walk_faster_than_its_stride_is_refused_naming_the_segment() {
    let s = shipped("hexapod");
    let legs = Legs::new(&s.model).expect("six legs");
    // Ripple: feet down 2/3 of 2 s; 60 mm/s sweeps 80 mm, over 60.
    let err = plan_walk(&legs, &forward(60.0, 5.0), &standing(&s)).expect_err("too fast");
    match err {
        WalkError::Stride {
            segment, needed_mm, ..
        } => {
            assert_eq!(segment, 0);
            assert!((needed_mm - 80.0).abs() < 1e-9, "{needed_mm}");
        }
        e => panic!("{e}"),
    }
}

#[test]
fn an_arm_has_no_legs() {
    let s = shipped("so101");
    assert!(matches!(
        Legs::new(&s.model),
        Err(IkError::UnknownFrame { .. })
    ));
}

/// How many feet are off the ground (above the standing height by more
/// than 0.01 mm) at each sample of a walk.
fn lifted_counts(s: &Shipped, legs: &Legs, plan: &servobus_kinematics::WalkPlan) -> Vec<usize> {
    let mut poses = Poses::new(&s.model);
    let mut feet = vec![Point3::origin(); legs.len()];
    plan.samples
        .iter()
        .map(|sample| {
            legs.feet(&sample.q, &mut poses, &mut feet);
            // Standing: every foot 40 mm below its hip.
            feet.iter().filter(|p| p.z > -40.0 + 0.01).count()
        })
        .collect()
}

#[test]
fn each_gait_lifts_as_many_legs_at_once_as_it_should() {
    let s = shipped("hexapod");
    let legs = Legs::new(&s.model).expect("six legs");
    // Tripod: three at once; ripple: one a side; wave: one.
    for (gait, most) in [(Gait::Tripod, 3), (Gait::Ripple, 2), (Gait::Wave, 1)] {
        let walk = Walk {
            gait,
            stride_mm: None,
            ..forward(20.0, 6.0)
        };
        let plan = plan_walk(&legs, &walk, &standing(&s)).expect("walks");
        let counts = lifted_counts(&s, &legs, &plan);
        let top = counts.iter().copied().max().unwrap_or(0);
        assert_eq!(top, most, "{gait:?}");
        assert!(plan.min_margin_mm > 0.0, "{gait:?}: {}", plan.min_margin_mm);
    }
}

#[test]
fn a_body_move_keeps_every_foot_where_it_stands() {
    let s = shipped("hexapod");
    let legs = Legs::new(&s.model).expect("six legs");
    let start = standing(&s);
    let mut poses = Poses::new(&s.model);
    let mut world = vec![Point3::origin(); legs.len()];
    legs.feet(&start, &mut poses, &mut world);
    // Up 20 mm, rolled 8 deg, turned 5 deg.
    let to = servobus_kinematics::Isometry3::from_parts(
        servobus_kinematics::Vector3::new(0.0, 0.0, 20.0).into(),
        servobus_kinematics::UnitQuaternion::from_euler_angles(
            8f64.to_radians(),
            0.0,
            5f64.to_radians(),
        ),
    );
    let line = PoseLine::new(servobus_kinematics::Isometry3::identity(), to);
    let samples = legs
        .body_move(&line, &world, &start, 1.0, linear(1.0), 0.02)
        .expect("reachable");
    assert_eq!(samples.len(), 51);
    let mut feet = vec![Point3::origin(); legs.len()];
    for (k, sample) in samples.iter().enumerate() {
        legs.feet(&sample.q, &mut poses, &mut feet);
        let body = line.at(k as f64 / 50.0);
        for (f, w) in feet.iter().zip(&world) {
            let seen = body * f;
            assert!((seen - w).norm() < 1e-6, "sample {k}: {seen} vs {w}");
        }
    }
}
