//! Closed-form leg IK on the shipped hexapod.

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use servobus_kinematics::{IkError, LegIk, Point3, Poses};

use crate::robots::{shipped, LEGS};

#[test]
fn round_trips_10000_random_reachable_feet_per_leg() {
    let s = shipped("hexapod");
    let mut rng = SmallRng::seed_from_u64(25);
    let mut poses = Poses::new(&s.model);
    let home = [0.0, 30f64.to_radians(), -60f64.to_radians()];
    for leg in LEGS {
        let ik = LegIk::new(&s.model, &format!("foot_{leg}")).expect("a leg");
        let joints = ik.joints();
        let foot = s.model.frame_index(&format!("foot_{leg}")).expect("foot");
        for _ in 0..10_000 {
            let mut q = vec![0.0; s.names.len()];
            for &j in &joints {
                let (lo, hi) = s.model.limits(j).expect("limits");
                q[j] = rng.gen_range(lo..hi);
            }
            s.model.forward(&q, &mut poses);
            let target = Point3::from(poses.frame(foot).expect("foot").translation.vector);
            let got = match ik.solve(&target, home) {
                Ok(got) => got,
                // The knee within a degree of straight or folded flat.
                Err(IkError::Singular { .. }) => continue,
                Err(e) => panic!("{leg}: {e} for {q:?}"),
            };
            for (k, &j) in joints.iter().enumerate() {
                q[j] = got[k];
            }
            s.model.forward(&q, &mut poses);
            let reached = Point3::from(poses.frame(foot).expect("foot").translation.vector);
            let miss = (reached - target).norm();
            assert!(miss < 0.01, "{leg}: missed by {miss} mm");
        }
    }
}

#[test]
fn keeps_the_knee_of_the_previous_solution() {
    let s = shipped("hexapod");
    let ik = LegIk::new(&s.model, "foot_front_left").expect("a leg");
    // 275 mm out from the hip (110, 70), level with it: the femur axis is
    // 230 away, so the knee bends 35 deg either way, both inside the limits.
    let target = Point3::new(110.0, 345.0, 0.0);
    let up = ik.solve(&target, [0.0, 0.5, -1.0]).expect("reachable");
    let down = ik.solve(&target, [0.0, -0.5, 1.0]).expect("reachable");
    assert!(up[1] > 0.0 && up[2] < 0.0, "knee up: {up:?}");
    assert!(down[1] < 0.0 && down[2] > 0.0, "knee down: {down:?}");
}

#[test]
fn refuses_a_foot_out_of_reach_with_the_distance_short() {
    let s = shipped("hexapod");
    let ik = LegIk::new(&s.model, "foot_front_left").expect("a leg");
    // 500 out from the hip at its height: femur axis 455 away, leg 240 long.
    match ik.solve(&Point3::new(110.0, 570.0, 0.0), [0.0; 3]) {
        Err(IkError::Unreachable { short }) => assert!((short - 215.0).abs() < 1e-9, "{short}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn refuses_a_foot_on_the_coxa_axis() {
    let s = shipped("hexapod");
    let ik = LegIk::new(&s.model, "foot_middle_right").expect("a leg");
    assert!(matches!(
        ik.solve(&Point3::new(0.0, -90.0, -100.0), [0.0; 3]),
        Err(IkError::Singular { .. })
    ));
}

#[test]
fn refuses_a_knee_within_a_degree_of_straight_as_a_singularity() {
    let s = shipped("hexapod");
    let ik = LegIk::new(&s.model, "foot_front_left").expect("a leg");
    // Level with the hip (110, 70), out along y: the femur axis is 45 out,
    // femur and tibia 80 + 160. At 239.995 from the femur axis the knee is
    // bent acos((239.995^2 - 80^2 - 160^2) / (2 * 80 * 160)) = 0.79 deg;
    // at 239 it is 11.1 deg, and solved.
    assert!(matches!(
        ik.solve(&Point3::new(110.0, 70.0 + 45.0 + 239.995, 0.0), [0.0; 3]),
        Err(IkError::Singular { .. })
    ));
    let q = ik
        .solve(&Point3::new(110.0, 70.0 + 45.0 + 239.0, 0.0), [0.0; 3])
        .expect("bent enough");
    assert!((q[2].abs().to_degrees() - 11.1).abs() < 0.05, "{q:?}");
}

#[test]
fn refuses_a_foot_beyond_the_coxa_limit_naming_it() {
    let s = shipped("hexapod");
    let ik = LegIk::new(&s.model, "foot_front_left").expect("a leg");
    // 200 ahead of the hip, 50 out: the coxa would turn 76 deg (limit 45).
    match ik.solve(&Point3::new(310.0, 120.0, -40.0), [0.0; 3]) {
        Err(IkError::JointLimit { joint, .. }) => assert_eq!(joint, "front_left_coxa"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn an_arm_is_not_a_leg() {
    let s = shipped("so101");
    assert!(matches!(
        LegIk::new(&s.model, "tool"),
        Err(IkError::Unsupported { .. })
    ));
}
