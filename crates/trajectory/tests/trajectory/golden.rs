//! Cases computed by hand, and the timed-keyframe errors.

use crate::common;

use servobus_trajectory::{
    plan, JointLimits, JointState, Keyframe, OnLimit, PlanError, PlanOptions, Quantity, TimedShape,
    Trajectory,
};

fn at(traj: &Trajectory, t: f64) -> Vec<JointState> {
    let mut out = vec![JointState::default(); traj.joints()];
    traj.sample(t, &mut out);
    out
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9
}

/// One joint moved from rest at 0 to rest at `d`, as fast as `limit`
/// allows.
fn move_one(limit: JointLimits, d: f64) -> Trajectory {
    plan(
        &[limit],
        &[Keyframe::new([0.0]), Keyframe::new([d])],
        &PlanOptions::default(),
    )
    .expect("plan")
}

/// Joint 0 at time `t` is at `(position, velocity, acceleration)`.
fn assert_state(traj: &Trajectory, t: f64, (p, v, a): (f64, f64, f64)) {
    let s = at(traj, t)[0];
    assert!(
        close(s.position, p) && close(s.velocity, v) && close(s.acceleration, a),
        "at {t} s: {s:?}, expected ({p}, {v}, {a})"
    );
}

/// d = 4, v = 2, a = 2, no jerk limit: accelerate 1 s (1 unit), cruise
/// 1 s at 2 (2 units), decelerate 1 s: T = 3 s.
#[test]
fn symmetric_trapezoid() {
    let traj = move_one(JointLimits::new(2.0, 2.0, None), 4.0);
    assert!(close(traj.duration(), 3.0), "{}", traj.duration());
    assert_state(&traj, 0.5, (0.25, 1.0, 2.0));
    assert_state(&traj, 1.5, (2.0, 2.0, 0.0));
    assert_state(&traj, 2.5, (3.75, 1.0, -2.0));
    let sum = traj.joint_summary(0).expect("joint 0");
    assert!(close(sum.peak_velocity, 2.0) && close(sum.peak_acceleration, 2.0));
    assert_eq!(
        sum.peak_jerk,
        f64::INFINITY,
        "a trapezoid's acceleration jumps"
    );
}

/// v = 10 (never reached), a = 2, j = 4, d = 3: jerk 0.5 s (a reaches 2),
/// constant acceleration 0.5 s, jerk 0.5 s: peak speed
/// 2 * 0.5 + 2 * 0.5 = 2 at t = 1.5, covering 1.5; the mirror image
/// decelerates: T = 3 s with no cruise.
#[test]
fn double_s_below_max_velocity() {
    let limits = [JointLimits::new(10.0, 2.0, Some(4.0))];
    let traj = move_one(limits[0], 3.0);
    assert!(close(traj.duration(), 3.0), "{}", traj.duration());
    // End of the first jerk phase: p = j t^3 / 6, v = j t^2 / 2, a = j t.
    assert_state(&traj, 0.5, (4.0 * 0.125 / 6.0, 0.5, 2.0));
    assert_state(&traj, 1.5, (1.5, 2.0, 0.0));
    let sum = traj.joint_summary(0).expect("joint 0");
    assert!(
        close(sum.peak_velocity, 2.0)
            && close(sum.peak_acceleration, 2.0)
            && close(sum.peak_jerk, 4.0),
        "{sum:?}"
    );
    common::check(&traj, &limits, &[3.0], true);
}

/// A joint that does not move stays put, at rest, while the other one
/// sets the duration; a joint with a shorter move is stretched (lower
/// cruise speed), not made to wait: with d = 1, a = 2 and T = 3 its cruise
/// speed solves v^2 / 2 - 3 v + 1 = 0, v = 3 - sqrt(7).
#[test]
fn still_joint_and_stretched_joint() {
    let l = JointLimits::new(2.0, 2.0, None);
    let limits = [l, l, l];
    let traj = plan(
        &limits,
        &[
            Keyframe::new([0.0, 0.7, 0.0]),
            Keyframe::new([4.0, 0.7, 1.0]),
        ],
        &PlanOptions::default(),
    )
    .expect("plan");
    assert!(close(traj.duration(), 3.0));
    for i in 0..=30 {
        let s = at(&traj, i as f64 * 0.1)[1];
        assert_eq!(s, JointState::at_rest(0.7));
    }
    let still = traj.joint_summary(1).expect("joint 1");
    assert_eq!(
        (still.peak_velocity, still.min_position, still.max_position),
        (0.0, 0.7, 0.7)
    );
    let stretched = traj.joint_summary(2).expect("joint 2");
    assert!(
        close(stretched.peak_velocity, 3.0 - 7f64.sqrt()),
        "{stretched:?}"
    );
    // Still moving just before the end: stretched, not idling.
    assert!(at(&traj, 2.9)[2].velocity > 0.0);
}

#[test]
fn timed_keyframes_are_hit_on_time() {
    let limits = [JointLimits::new(5.0, 50.0, Some(500.0)); 2];
    let keyframes = [
        Keyframe::new([0.0, 0.0]),
        Keyframe::new([0.5, -0.3]).at(1.0),
        Keyframe::new([1.0, 0.2]).at(2.0),
        Keyframe::new([0.2, 0.0]).at(3.5),
    ];
    for shape in [
        TimedShape::Cubic,
        TimedShape::Monotone,
        TimedShape::MinimumJerk,
    ] {
        let traj = plan(
            &limits,
            &keyframes,
            &PlanOptions {
                shape,
                ..PlanOptions::default()
            },
        )
        .expect("plan");
        assert!(close(traj.duration(), 3.5));
        let ends: Vec<f64> = traj.segments().iter().map(|s| s.end).collect();
        assert_eq!(ends, [1.0, 2.0, 3.5]);
        common::check_keyframes(&traj, &keyframes);
        common::check(&traj, &limits, &[0.2, 0.0], true);
    }
}

#[test]
fn timed_segment_beyond_a_limit_is_named_or_stretched() {
    let limits = [
        JointLimits::new(1.0, 50.0, None),
        JointLimits::new(1.0, 4.0, None),
    ];
    let keyframes = [
        Keyframe::new([0.0, 0.0]),
        Keyframe::new([0.1, 0.1]).at(1.0),
        Keyframe::new([0.1, 1.5]).at(1.5),
    ];
    // Minimum-jerk segments are independent: the fast segment is the one
    // arriving at keyframe 2. (A cubic spline spreads the effort over its
    // neighbours, so it may already fail on the way to keyframe 1.)
    let min_jerk = PlanOptions {
        shape: TimedShape::MinimumJerk,
        ..PlanOptions::default()
    };
    let err = plan(&limits, &keyframes, &min_jerk).expect_err("too fast");
    match err {
        PlanError::LimitExceeded {
            keyframe: 2,
            joint: 1,
            quantity,
            peak,
            limit,
        } => {
            assert!(matches!(
                quantity,
                Quantity::Velocity | Quantity::Acceleration
            ));
            assert!(peak > limit);
            // Minimum-jerk peaks: v = 1.875 d / h, a = 5.7735 d / h^2.
            let expected = if quantity == Quantity::Velocity {
                1.875 * 1.4 / 0.5
            } else {
                5.773_502_7 * 1.4 / 0.25
            };
            assert!(
                (peak - expected).abs() < 1e-3 * expected,
                "{peak} vs {expected}"
            );
        }
        other => panic!("unexpected {other:?}"),
    }
    let spline = PlanOptions {
        shape: TimedShape::Cubic,
        ..PlanOptions::default()
    };
    match plan(&limits, &keyframes, &spline) {
        Err(PlanError::LimitExceeded { joint: 1, .. }) => {}
        other => panic!("unexpected {other:?}"),
    }
    // Shape-preserving (the default): joint 1 cannot cover 1.4 in 0.5 s
    // even from rest to rest (1.4 s at 1 per s plus 0.25 s of ramps).
    match plan(&limits, &keyframes, &PlanOptions::default()) {
        Err(PlanError::TooSoon {
            keyframe: 2,
            needed,
            available,
        }) => assert!(
            (needed - 1.65).abs() < 1e-9 && close(available, 0.5),
            "{needed}"
        ),
        other => panic!("unexpected {other:?}"),
    }
    let options = PlanOptions {
        on_limit: OnLimit::Stretch,
        ..PlanOptions::default()
    };
    let traj = plan(&limits, &keyframes, &options).expect("stretched");
    assert!(traj.duration() > 1.5);
    common::check(&traj, &limits, &[0.1, 1.5], true);
    common::check_keyframes(&traj, &keyframes);
}

#[test]
fn untimed_then_timed_arrives_on_time_or_says_too_soon() {
    let limits = [JointLimits::new(1.0, 2.0, Some(10.0))];
    let kfs = |t| {
        [
            Keyframe::new([0.0]),
            Keyframe::new([1.0]),
            Keyframe::new([2.0]).at(t),
        ]
    };
    let traj = plan(&limits, &kfs(5.0), &PlanOptions::default()).expect("plan");
    assert!(close(traj.duration(), 5.0));
    common::check(&traj, &limits, &[2.0], true);
    match plan(&limits, &kfs(1.0), &PlanOptions::default()) {
        Err(PlanError::TooSoon {
            keyframe: 2,
            needed,
            available,
        }) => assert!(needed > available && close(available, 1.0)),
        other => panic!("unexpected {other:?}"),
    }
}

#[test]
fn invalid_input_is_refused() {
    let l = [JointLimits::new(1.0, 1.0, None).with_positions(-1.0, 1.0)];
    let o = PlanOptions::default();
    assert!(matches!(
        plan(&l, &[Keyframe::new([0.0]), Keyframe::new([2.0])], &o),
        Err(PlanError::OutOfRange {
            keyframe: 1,
            joint: 0,
            ..
        })
    ));
    assert!(matches!(
        plan(&l, &[Keyframe::new([0.0, 1.0])], &o),
        Err(PlanError::WrongJointCount { .. })
    ));
    assert!(matches!(plan(&l, &[], &o), Err(PlanError::NoKeyframes)));
    assert!(matches!(
        plan(&l, &[Keyframe::new([0.0]).at(1.0)], &o),
        Err(PlanError::FirstKeyframeTime { .. })
    ));
    let kf = [
        Keyframe::new([0.0]),
        Keyframe::new([0.5]).at(2.0),
        Keyframe::new([0.0]).at(1.0),
    ];
    assert!(matches!(
        plan(&l, &kf, &o),
        Err(PlanError::TimeNotIncreasing { keyframe: 2, .. })
    ));
    let bad = [JointLimits::new(0.0, 1.0, None)];
    assert!(matches!(
        plan(&bad, &[Keyframe::new([0.0])], &o),
        Err(PlanError::InvalidLimits { joint: 0, .. })
    ));
}

#[test]
fn repeat_plays_the_list_again() {
    let limits = [JointLimits::new(2.0, 8.0, Some(80.0))];
    let keyframes = [
        Keyframe::new([0.0]),
        Keyframe::new([1.0]),
        Keyframe::new([0.0]),
    ];
    let once = plan(&limits, &keyframes, &PlanOptions::default()).expect("once");
    let thrice = plan(
        &limits,
        &keyframes,
        &PlanOptions {
            repeat: 3,
            ..PlanOptions::default()
        },
    )
    .expect("thrice");
    assert!((thrice.duration() - 3.0 * once.duration()).abs() < 1e-9);
    assert_eq!(thrice.segments().len(), 6);
    assert_eq!(thrice.segments()[5].cycle, 2);
}
