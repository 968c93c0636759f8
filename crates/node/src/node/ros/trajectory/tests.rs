//! The planner of ROS 2 trajectories, on the SO-101's joints and limits.

use servobus_robot::config::Units;

use super::*;
use crate::ros2::{Header, JointTrajectory, JointTrajectoryPoint, RosDuration};

const NAMES: [&str; 6] = [
    "shoulder_pan",
    "shoulder_lift",
    "elbow_flex",
    "wrist_flex",
    "wrist_roll",
    "gripper",
];

fn robot() -> RosRobot {
    let deg = |d: f64| d.to_radians();
    RosRobot {
        names: NAMES.iter().map(|s| s.to_string()).collect(),
        limits: (0..6)
            .map(|j| {
                Some(Limits {
                    min: deg(-110.0),
                    max: deg(110.0),
                    max_velocity: deg(if j == 1 { 150.0 } else { 180.0 }),
                })
            })
            .collect(),
        units: Units::Deg,
    }
}

fn point(positions: &[f64], t: f64) -> JointTrajectoryPoint {
    JointTrajectoryPoint {
        positions: positions.to_vec(),
        time_from_start: RosDuration::from_secs_f64(t),
        ..Default::default()
    }
}

fn trajectory(joints: &[&str], points: Vec<JointTrajectoryPoint>) -> JointTrajectory {
    JointTrajectory {
        header: Header::default(),
        joint_names: joints.iter().map(|s| s.to_string()).collect(),
        points,
    }
}

/// Every joint heading for 0.1 rad times its index.
fn heading(j: usize) -> Option<f64> {
    Some(0.1 * j as f64)
}

fn at(now: f64, start: f64) -> Start<'static> {
    Start {
        now,
        start,
        position: &heading,
    }
}

fn refused(traj: &JointTrajectory, from: &Start<'_>) -> Refusal {
    match plan(traj, &robot(), from) {
        Ok(p) => panic!("planned: {p:?}"),
        Err(r) => r,
    }
}

#[test]
fn points_are_due_at_the_start_plus_their_time_after_a_mark_already_past() {
    let traj = trajectory(
        &["elbow_flex", "shoulder_pan"],
        vec![
            point(&[0.2, 0.1], 0.5),
            point(&[0.4, -0.1], 1.0),
            point(&[0.1, 0.3], 2.0),
            point(&[0.0, 0.0], 3.0),
        ],
    );
    let p = plan(&traj, &robot(), &at(10.0, 10.0)).expect("planned");
    assert_eq!(p.joints, vec![2, 0], "by name, in the message's order");
    assert_eq!(
        p.times,
        vec![10.0 - MARK_AGE, 10.5, 11.0, 12.0, 13.0, 13.0 + SETTLE]
    );
    // The mark sits where each joint is heading; then the points, the
    // last one held.
    assert_eq!(p.positions[0], vec![0.2, 0.2, 0.4, 0.1, 0.0, 0.0]);
    assert_eq!(p.positions[1], vec![0.0, 0.1, -0.1, 0.3, 0.0, 0.0]);
    assert_eq!((p.start, p.end), (10.0, 13.0));
    assert_eq!(p.last, vec![0.0, 0.0]);
    // The chunk names only the joints given: the others keep their targets.
    let chunk = p.chunk(&robot());
    let expected = Chunk::timed(
        p.times.clone(),
        vec![
            ("elbow_flex".into(), p.positions[0].clone()),
            ("shoulder_pan".into(), p.positions[1].clone()),
        ],
    );
    assert_eq!(chunk, expected);
}

#[test]
fn a_start_ahead_holds_until_it_and_points_already_past_are_skipped() {
    let traj = trajectory(&["gripper"], vec![point(&[0.3], 1.0), point(&[0.6], 2.0)]);
    // header.stamp 2 s ahead: held where the gripper heads until then.
    let p = plan(&traj, &robot(), &at(10.0, 12.0)).expect("planned");
    assert_eq!(
        p.times,
        vec![10.0 - MARK_AGE, 12.0, 13.0, 14.0, 14.0 + SETTLE]
    );
    assert_eq!(p.positions[0], vec![0.5, 0.5, 0.3, 0.6, 0.6]);
    // Started 1.5 s ago: the first point is past, the second still ahead.
    let p = plan(&traj, &robot(), &at(10.0, 8.5)).expect("planned");
    assert_eq!(p.times, vec![10.0 - MARK_AGE, 10.5, 10.5 + SETTLE]);
    assert_eq!(p.positions[0], vec![0.5, 0.6, 0.6]);
    // Wholly past: refused, and why.
    let r = refused(&traj, &at(10.0, 7.0));
    assert_eq!(r.code, Fjt::OLD_HEADER_TIMESTAMP);
    assert!(r.why.contains("ended 1.000 s before it arrived"), "{r}");
}

#[test]
fn joints_the_robot_does_not_have_are_refused_by_name() {
    let traj = trajectory(&["elbow_flex", "thumb"], vec![point(&[0.1, 0.1], 1.0)]);
    let r = refused(&traj, &at(0.0, 0.0));
    assert_eq!(r.code, Fjt::INVALID_JOINTS);
    assert!(
        r.why.contains("`thumb`") && r.why.contains("shoulder_pan"),
        "{r}"
    );
    let twice = trajectory(&["gripper", "gripper"], vec![point(&[0.1, 0.1], 1.0)]);
    assert!(refused(&twice, &at(0.0, 0.0)).why.contains("named twice"));
    let none = trajectory(&[], vec![point(&[], 1.0)]);
    assert_eq!(refused(&none, &at(0.0, 0.0)).code, Fjt::INVALID_JOINTS);
}

#[test]
fn a_point_past_a_limit_is_refused_with_the_joint_the_point_and_the_limit() {
    let traj = trajectory(
        &["shoulder_pan"],
        vec![point(&[0.5], 1.0), point(&[2.5], 3.0)],
    );
    let r = refused(&traj, &at(0.0, 0.0));
    assert_eq!(r.code, Fjt::INVALID_GOAL);
    for word in [
        "point 1",
        "`shoulder_pan`",
        "143.24 deg",
        "above its maximum",
        "110.00 deg",
    ] {
        assert!(r.why.contains(word), "{word}: {r}");
    }
}

#[test]
fn a_piece_faster_than_the_velocity_limit_is_refused() {
    // 1 rad in 0.2 s: 286 deg/s, the pan's limit is 180.
    let traj = trajectory(
        &["shoulder_pan"],
        vec![point(&[0.0], 1.0), point(&[1.0], 1.2)],
    );
    let r = refused(&traj, &at(0.0, 0.0));
    assert_eq!(r.code, Fjt::INVALID_GOAL);
    assert!(r.why.contains("from point 0 to point 1"), "{r}");
    assert!(
        r.why.contains("286.5 deg/s") && r.why.contains("180.0 deg/s"),
        "{r}"
    );
    // The same move in 0.4 s (143 deg/s) is fine.
    let slow = trajectory(
        &["shoulder_pan"],
        vec![point(&[0.0], 1.0), point(&[1.0], 1.4)],
    );
    assert!(plan(&slow, &robot(), &at(0.0, 0.0)).is_ok());
}

#[test]
fn malformed_points_are_refused_with_the_point() {
    let cases: Vec<(Vec<JointTrajectoryPoint>, &str)> = vec![
        (vec![], "has 0 points"),
        (vec![point(&[0.1, 0.2], 1.0)], "point 0 has 2 positions"),
        (vec![point(&[f64::NAN], 1.0)], "not a number"),
        (
            vec![point(&[0.1], 1.0), point(&[0.2], 1.0)],
            "point 1's time_from_start (1 s) is not after point 0's (1 s)",
        ),
        (
            vec![JointTrajectoryPoint {
                velocities: vec![0.0, 0.0],
                ..point(&[0.1], 1.0)
            }],
            "point 0 has 2 velocities",
        ),
        (
            vec![JointTrajectoryPoint {
                time_from_start: RosDuration {
                    sec: -1,
                    nanosec: 0,
                },
                ..point(&[0.1], 1.0)
            }],
            "is not a time from the start",
        ),
    ];
    for (points, says) in cases {
        let r = refused(&trajectory(&["gripper"], points), &at(0.0, 0.0));
        assert_eq!(r.code, Fjt::INVALID_GOAL, "{r}");
        assert!(r.why.contains(says), "{says}: {r}");
    }
}

/// Central differences of `q` at the interior samples.
fn slopes(times: &[f64], q: &[f64]) -> Vec<f64> {
    q.windows(2)
        .zip(times.windows(2))
        .map(|(w, t)| (w[1] - w[0]) / (t[1] - t[0]))
        .collect()
}

#[test]
fn velocities_given_make_a_cubic_through_the_points_sampled_every_20_ms() {
    let with_v = |q: f64, v: f64, t: f64| JointTrajectoryPoint {
        velocities: vec![v],
        ..point(&[q], t)
    };
    let traj = trajectory(
        &["elbow_flex"],
        vec![
            with_v(0.0, 0.0, 0.0),
            with_v(0.5, 0.8, 1.0),
            with_v(1.0, 0.0, 2.0),
        ],
    );
    let p = plan(&traj, &robot(), &at(0.0, 0.0)).expect("planned");
    // The points (at 0 s: skipped, on arrival) and 49 samples per piece.
    let times = &p.times[1..p.times.len() - 1];
    let q = &p.positions[0][1..times.len() + 1];
    assert_eq!(times.len(), 2 * 50, "{times:?}");
    assert!(times.windows(2).all(|w| w[1] - w[0] <= 0.02 + 1e-12));
    let at_1 = times
        .iter()
        .position(|&t| (t - 1.0).abs() < 1e-12)
        .expect("a sample at 1 s");
    assert!((q[at_1] - 0.5).abs() < 1e-12, "through the point");
    // Its slopes on either side of the point are the velocity given.
    let v = slopes(times, q);
    assert!(
        (v[at_1 - 1] - 0.8).abs() < 0.01 && (v[at_1] - 0.8).abs() < 0.01,
        "{v:?}"
    );
    // Rest at the end, and no slope above the curve's own peak.
    assert!(v.last().expect("slopes").abs() < 0.02);
    assert!(v.iter().all(|s| s.abs() < 1.2), "{v:?}");
}

#[test]
fn accelerations_with_velocities_make_a_quintic_that_keeps_both() {
    let full = |q: f64, v: f64, a: f64, t: f64| JointTrajectoryPoint {
        velocities: vec![v],
        accelerations: vec![a],
        ..point(&[q], t)
    };
    let a = full(0.0, 0.0, 2.0, 0.0);
    let b = full(0.6, 0.4, -1.0, 1.0);
    // Second differences at the ends are the accelerations given.
    let h = 1e-4;
    let second = |s: f64| {
        (hermite(&a, &b, 0, 1.0, s + h) - 2.0 * hermite(&a, &b, 0, 1.0, s)
            + hermite(&a, &b, 0, 1.0, s - h))
            / (h * h)
    };
    assert!((second(h) - 2.0).abs() < 0.01, "{}", second(h));
    assert!((second(1.0 - h) + 1.0).abs() < 0.01, "{}", second(1.0 - h));
    let slope_end = (hermite(&a, &b, 0, 1.0, 1.0) - hermite(&a, &b, 0, 1.0, 1.0 - h)) / h;
    assert!((slope_end - 0.4).abs() < 1e-3, "{slope_end}");
    assert!((hermite(&a, &b, 0, 1.0, 1.0) - 0.6).abs() < 1e-12);
    // Without velocities on both ends a piece stays straight.
    let straight = trajectory(&["elbow_flex"], vec![a, point(&[0.6], 1.0)]);
    let p = plan(&straight, &robot(), &at(-1.0, 0.0)).expect("planned");
    assert_eq!(p.times, vec![-1.0 - MARK_AGE, 0.0, 1.0, 1.0 + SETTLE]);
}

#[test]
fn a_curve_that_overshoots_a_limit_between_points_is_refused() {
    // Both points inside the pan's 110 deg, but leaving the second at
    // speed the cubic bulges past it.
    let with_v = |q: f64, v: f64, t: f64| JointTrajectoryPoint {
        velocities: vec![v],
        ..point(&[q], t)
    };
    let traj = trajectory(
        &["shoulder_pan"],
        vec![with_v(1.80, 2.5, 0.0), with_v(1.80, -2.5, 1.0)],
    );
    let r = refused(&traj, &at(-1.0, 0.0));
    assert!(r.why.contains("between points 0 and 1"), "{r}");
}
