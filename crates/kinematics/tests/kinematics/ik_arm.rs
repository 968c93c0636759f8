//! Arm IK on the shipped SO-101.

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use servobus_kinematics::{ArmIk, ArmTarget, IkError, Point3, UnitQuaternion, Vector3};

use crate::robots::{shipped, Shipped};

fn home(ik: &ArmIk, names: &[String]) -> Vec<f64> {
    // so101.yaml's home: lift -90, elbow 90, wrist 45.
    ik.joints()
        .iter()
        .map(|&j| match names[j].as_str() {
            "shoulder_lift" => -90f64.to_radians(),
            "elbow_flex" => 90f64.to_radians(),
            "wrist_flex" => 45f64.to_radians(),
            _ => 0.0,
        })
        .collect()
}

/// Solves 10,000 random reachable tool poses (position, pitch and roll of
/// a random pose inside the limits), each from `seed(q)`, and returns how
/// many were refused; every answer given is checked.
fn round_trips(seed: impl Fn(&mut SmallRng, &[f64]) -> Vec<f64>) -> usize {
    round_trips_on(&shipped("so101"), seed)
}

/// [`round_trips`] on any SO-101 geometry (the shipped one, one imported
/// from the URDF).
pub(crate) fn round_trips_on(
    s: &Shipped,
    seed: impl Fn(&mut SmallRng, &[f64]) -> Vec<f64>,
) -> usize {
    let ik = ArmIk::new(&s.model, "tool").expect("an arm");
    assert_eq!(
        ik.joints().len(),
        5,
        "pan, lift, elbow, wrist flex and roll"
    );
    let mut rng = SmallRng::seed_from_u64(101);
    let mut out = vec![0.0; 5];
    let mut refused = 0;
    for _ in 0..10_000 {
        let q: Vec<f64> = ik
            .joints()
            .iter()
            .map(|&j| {
                let (lo, hi) = s.model.limits(j).expect("limits");
                rng.gen_range(lo..hi)
            })
            .collect();
        let goal = ik.frame_pose(&q);
        let (roll, pitch, _) = goal.rotation.euler_angles();
        let target = ArmTarget {
            xyz: Point3::from(goal.translation.vector),
            pitch: Some(pitch),
            roll: Some(roll),
        };
        let start = seed(&mut rng, &q);
        if ik.solve(&target, &start, &mut out).is_err() {
            refused += 1;
            continue;
        }
        assert!(ik.within_limits(&out));
        let got = ik.frame_pose(&out);
        let miss = (got.translation.vector - goal.translation.vector).norm();
        assert!(miss < 0.01, "missed by {miss} mm for {q:?}");
        // Orientation up to the yaw the pan chooses: got = Rz(yaw) * want
        // for some yaw, so got * want^-1 keeps the z axis where it is.
        let want = UnitQuaternion::from_euler_angles(roll, pitch, 0.0);
        let z = Vector3::z();
        let off = ((got.rotation * want.inverse()) * z).angle(&z).to_degrees();
        assert!(off < 0.01, "orientation off by {off} deg for {q:?}");
    }
    refused
}

#[test]
fn round_trips_10000_random_poses_from_a_previous_solution_nearby() {
    // As inside a move: the previous solution is within 10 deg per joint.
    let refused = round_trips(|rng, q| {
        q.iter()
            .map(|v| v + rng.gen_range(-10f64..10.0).to_radians())
            .collect()
    });
    // One of the 10,000 (pointing straight down at the edge of a limit) is
    // refused with a reason; none is answered wrongly.
    eprintln!("refused from nearby: {refused} of 10000");
    assert!(refused <= 5, "{refused} of 10000 refused");
}

#[test]
fn round_trips_10000_random_poses_from_home() {
    // From the home pose: the search restarts from spread-out poses when
    // home leads nowhere. A few poses, folded back over the arm at the
    // edges of the limits, are not found: at most 0.1 %.
    let s = shipped("so101");
    let ik = ArmIk::new(&s.model, "tool").expect("an arm");
    let start = home(&ik, &s.names);
    let refused = round_trips(|_, _| start.clone());
    eprintln!("refused from home: {refused} of 10000");
    assert!(refused <= 10, "{refused} of 10000 refused");
}

#[test]
fn a_move_in_small_steps_never_flips_a_joint() {
    let s = shipped("so101");
    let ik = ArmIk::new(&s.model, "tool").expect("an arm");
    let mut out = vec![0.0; 5];
    // A 200 mm straight line across the front, gripper pointing down, 69
    // below the lift axis (at 119.0). 30 mm higher, its ends would need
    // wrist_flex past its 95 deg limit.
    let target = |y: f64| ArmTarget {
        xyz: Point3::new(200.0, y, 50.0),
        pitch: Some(90f64.to_radians() - 1e-3),
        roll: Some(0.0),
    };
    ik.solve(&target(-100.0), &home(&ik, &s.names), &mut out)
        .expect("reachable");
    let mut q = out.clone();
    for k in 0..=200 {
        let y = -100.0 + f64::from(k);
        ik.solve(&target(y), &q, &mut out).expect("reachable");
        let jump = q
            .iter()
            .zip(&out)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            jump.to_degrees() < 5.0,
            "a {} deg jump at y {y}",
            jump.to_degrees()
        );
        q.copy_from_slice(&out);
    }
}

#[test]
fn refuses_a_target_out_of_reach_with_the_distance_short() {
    // Straight ahead at the lift axis's height (119.0): the lift axis is
    // 569.6 away; the arm reaches 116.0 (upper arm) + 135.0 (forearm) +
    // 159.43 (wrist flex axis to the tool, 159.23 along and 7.9 below the
    // roll axis) = 410.43 from it.
    let s = shipped("so101");
    let ik = ArmIk::new(&s.model, "tool").expect("an arm");
    let target = ArmTarget {
        xyz: Point3::new(600.0, 0.0, 119.0),
        pitch: None,
        roll: None,
    };
    let mut out = vec![0.0; 5];
    match ik.solve(&target, &home(&ik, &s.names), &mut out) {
        Err(IkError::Unreachable { short }) => {
            assert!((short - 159.17).abs() < 0.5, "short {short}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn refuses_a_roll_beyond_the_wrist_roll_limit_naming_it() {
    // The tool where it is at zero, rolled 170 deg: the tool itself is
    // rolled 2.789 deg on the roll joint, so wrist_roll (its axis is -x)
    // would go to -167.2; limit 160.
    let s = shipped("so101");
    let ik = ArmIk::new(&s.model, "tool").expect("an arm");
    let target = ArmTarget {
        xyz: Point3::new(352.53, -0.01, 228.87),
        pitch: Some(0.0),
        roll: Some(170f64.to_radians()),
    };
    let mut out = vec![0.0; 5];
    match ik.solve(&target, &[0.0; 5], &mut out) {
        Err(IkError::JointLimit { joint, .. }) => assert_eq!(joint, "wrist_roll"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn solving_allocates_nothing() {
    let s = shipped("so101");
    let ik = ArmIk::new(&s.model, "tool").expect("an arm");
    let seed = home(&ik, &s.names);
    let mut out = vec![0.0; 5];
    let target = ArmTarget {
        xyz: Point3::new(250.0, 50.0, 120.0),
        pitch: Some(0.5),
        roll: Some(0.0),
    };
    let (count, r) =
        servobus_alloc_count::allocations_during(|| ik.solve(&target, &seed, &mut out));
    assert!(r.is_ok(), "{r:?}");
    assert_eq!(count, 0);
}
