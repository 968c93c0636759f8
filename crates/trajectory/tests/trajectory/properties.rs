//! Property tests: random limits and keyframes; sampled motion never
//! exceeds a limit, is continuous, passes every keyframe and ends at rest.

use crate::common;

use proptest::prelude::*;
use servobus_trajectory::{
    plan, retarget, stop, JointLimits, JointState, Keyframe, OnLimit, PlanOptions, TimedShape,
};

/// The shortest stop of one joint from `s`, in closed form: (where it
/// comes to rest, how long it takes).
///
/// Without a jerk limit: full deceleration, |v| / a_max, over v|v| / 2a_max.
/// With one (j_max): the acceleration ramps to a peak A against the
/// motion (direction `d`), may hold it at a_max, and ramps back to zero
/// just as the velocity reaches zero. `d` opposes the velocity the joint
/// would have if its acceleration were ramped to zero at once
/// (v + a|a| / 2j). Summing the velocity each phase adds and asking for
/// zero gives, without a hold, A^2 = (a^2 - 2 d v j) / 2; when that A
/// exceeds a_max, the hold lasts (-d v - (2 a_max^2 - a^2) / 2j) / a_max.
/// Positions follow from constant-jerk phases.
fn stop_by_hand(l: &JointLimits, s: &JointState) -> (f64, f64) {
    let (p, v, a, am) = (s.position, s.velocity, s.acceleration, l.max_acceleration);
    let Some(jm) = l.max_jerk else {
        return (p + v * v.abs() / (2.0 * am), v.abs() / am);
    };
    let after_ramp = v + a * a.abs() / (2.0 * jm);
    if after_ramp == 0.0 && a == 0.0 {
        return (p, 0.0);
    }
    let d = if after_ramp > 0.0 { -1.0 } else { 1.0 };
    let peak = ((a * a - 2.0 * d * v * jm) / 2.0).max(0.0).sqrt();
    let (peak, hold) = if peak > am {
        (am, (-d * v - (2.0 * am * am - a * a) / (2.0 * jm)) / am)
    } else {
        (peak, 0.0)
    };
    let phases = [
        (d * jm, (peak - d * a) / jm),
        (0.0, hold),
        (-d * jm, peak / jm),
    ];
    let (mut p, mut v, mut a, mut t) = (p, v, a, 0.0);
    for (jerk, dt) in phases {
        p += v * dt + a * dt * dt / 2.0 + jerk * dt * dt * dt / 6.0;
        v += a * dt + jerk * dt * dt / 2.0;
        a += jerk * dt;
        t += dt;
    }
    (p, t)
}

fn limits_strategy() -> impl Strategy<Value = JointLimits> {
    (
        0.2f64..5.0,
        0.5f64..40.0,
        prop::option::weighted(0.8, 5.0f64..500.0),
    )
        .prop_map(|(v, a, j)| JointLimits::new(v, a, j).with_positions(-2.0, 2.0))
}

/// Joints, then keyframes with positions in the limits; some positions
/// repeat the previous one (a joint that pauses).
fn case() -> impl Strategy<Value = (Vec<JointLimits>, Vec<Vec<f64>>)> {
    (1usize..5, 2usize..8).prop_flat_map(|(nj, nk)| {
        (
            prop::collection::vec(limits_strategy(), nj),
            prop::collection::vec(
                prop::collection::vec(prop_oneof![3 => -2.0f64..2.0, 1 => Just(0.5)], nj),
                nk,
            ),
        )
    })
}

proptest! {
    // 64 cases by default (PROPTEST_CASES=N for a longer run).
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(64),
        ..ProptestConfig::default()
    })]

    #[test]
    fn untimed_within_limits((limits, kfs) in case(), stop_each in any::<bool>()) {
        let keyframes: Vec<Keyframe> = kfs.iter().cloned().map(Keyframe::new).collect();
        let options = PlanOptions { stop_at_keyframes: stop_each, ..PlanOptions::default() };
        let traj = plan(&limits, &keyframes, &options).expect("plan");
        common::check(&traj, &limits, &kfs[kfs.len() - 1], true);
        common::check_keyframes(&traj, &keyframes);
        // Untimed motion stays within the keyframes' range.
        for j in 0..limits.len() {
            let s = traj.joint_summary(j).expect("joint");
            let lo = kfs.iter().map(|k| k[j]).fold(f64::INFINITY, f64::min);
            let hi = kfs.iter().map(|k| k[j]).fold(f64::NEG_INFINITY, f64::max);
            prop_assert!(s.min_position >= lo - 1e-9 && s.max_position <= hi + 1e-9);
        }
    }

    #[test]
    fn timed_stretched_within_limits(
        (limits, kfs) in case(),
        gaps in prop::collection::vec(0.05f64..2.0, 8),
        timed in prop::collection::vec(any::<bool>(), 8),
        shape in prop_oneof![Just(TimedShape::Cubic), Just(TimedShape::Monotone), Just(TimedShape::MinimumJerk)],
        repeat in 1u32..3,
    ) {
        // Mixed timed and untimed keyframes; the cubic spline may leave
        // the position limits, which stretching cannot fix: widen them.
        let limits: Vec<JointLimits> = limits.into_iter().map(|l| l.with_positions(-50.0, 50.0)).collect();
        let mut t = 0.0;
        let keyframes: Vec<Keyframe> = kfs.iter().enumerate().map(|(k, p)| {
            t += gaps[k];
            let kf = Keyframe::new(p.clone());
            if k > 0 && timed[k] { kf.at(t) } else { kf }
        }).collect();
        let options = PlanOptions { shape, on_limit: OnLimit::Stretch, repeat, ..PlanOptions::default() };
        let traj = plan(&limits, &keyframes, &options).expect("plan");
        common::check(&traj, &limits, &kfs[kfs.len() - 1], true);
        common::check_keyframes(&traj, &keyframes);
        let segs = traj.segments();
        prop_assert_eq!(segs.len(), if kfs[0] == kfs[kfs.len() - 1] { (kfs.len() - 1) * repeat as usize } else { kfs.len() * repeat as usize - 1 });
        for w in segs.windows(2) {
            prop_assert!(w[0].end == w[1].start && w[0].start <= w[0].end);
        }
    }

    #[test]
    fn retarget_and_stop_within_limits(
        (limits, kfs) in case(),
        fv in prop::collection::vec(-1.0f64..1.0, 5),
        fa in prop::collection::vec(-1.0f64..1.0, 5),
    ) {
        // A state within the limits whose speed stays within the limit
        // while the acceleration is ramped to zero (otherwise exceeding it
        // is unavoidable).
        let states: Vec<JointState> = limits.iter().enumerate().map(|(j, l)| {
            let vm = l.max_velocity;
            let (a, ramp) = match l.max_jerk {
                Some(jm) => {
                    let a = fa[j] * l.max_acceleration.min(0.99 * (2.0 * jm * vm).sqrt());
                    (a, a.signum() * a * a / (2.0 * jm))
                }
                None => (0.0, 0.0),
            };
            // Speeds whose value after the ramp, v + ramp, is within +-vm.
            let (lo, hi) = ((-vm).max(-vm - ramp), vm.min(vm - ramp));
            let v = lo + 0.5 * (fv[j] + 1.0) * (hi - lo);
            JointState { position: kfs[0][j] * 0.5, velocity: v, acceleration: a }
        }).collect();
        let target = &kfs[kfs.len() - 1];
        let free: Vec<JointLimits> = limits.iter().map(|l| l.with_positions(-1e3, 1e3)).collect();
        let traj = retarget(&limits, &states, target).expect("retarget");
        common::check(&traj, &free, target, true);
        let mut s0 = vec![JointState::default(); limits.len()];
        traj.sample(0.0, &mut s0);
        // Continuous from the given state (acceleration only jumps for a
        // joint without a jerk limit).
        for ((a, b), l) in s0.iter().zip(&states).zip(&limits) {
            prop_assert!((a.position - b.position).abs() < 1e-12 && (a.velocity - b.velocity).abs() < 1e-12);
            if traj.duration() > 0.0 && l.max_jerk.is_some() {
                prop_assert!((a.acceleration - b.acceleration).abs() < 1e-9);
            }
        }
        let halt = stop(&limits, &states).expect("stop");
        // Where and when each joint comes to rest, worked out in closed
        // form (`stop_by_hand`), not read from the stop.
        let by_hand: Vec<(f64, f64)> =
            limits.iter().zip(&states).map(|(l, s)| stop_by_hand(l, s)).collect();
        let ends: Vec<f64> = by_hand.iter().map(|e| e.0).collect();
        let slowest = by_hand.iter().map(|e| e.1).fold(0.0, f64::max);
        prop_assert!(
            (halt.duration() - slowest).abs() <= 1e-6 * (1.0 + slowest),
            "the stop lasts {} s, the slowest joint needs {slowest} s", halt.duration()
        );
        let mut end = vec![JointState::default(); limits.len()];
        halt.sample(halt.duration() + 1.0, &mut end);
        for (j, (e, &q)) in end.iter().zip(&ends).enumerate() {
            prop_assert!(
                (e.position - q).abs() <= 1e-6 * (1.0 + q.abs()),
                "joint {} stops at {} s, by hand at {}", j, e.position, q
            );
        }
        let sampled: Vec<f64> = end.iter().map(|s| s.position).collect();
        common::check(&halt, &free, &sampled, true);
    }
}
